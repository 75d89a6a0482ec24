"""Schemas of a driving log's tables (``logs/<seq_id>/``): frames, ego poses, tracks, objects, map features."""

from __future__ import annotations

import pyarrow as pa

from storage.schemas.base import make_schema, vec

# ----------------------------------------------------------------------------- log tables
FRAMES_SCHEMA = make_schema(
    "frames",
    1,
    [
        ("seq_id", pa.string()),
        ("frame_idx", pa.int64()),
        ("timestamp_us", pa.int64()),
        ("camera", pa.string()),
        ("image_uri", pa.string()),  # EXR path relative to the log directory; "" when no pixels
        ("K", vec(9)),  # row-major 3x3 intrinsics
        ("cam_to_world", vec(16)),  # row-major 4x4, OpenCV camera -> world
        ("width", pa.int32()),
        ("height", pa.int32()),
        ("split", pa.string()),  # "train" | "test"
    ],
)

EGO_POSES_SCHEMA = make_schema(
    "ego_poses",
    1,
    [
        ("seq_id", pa.string()),
        ("frame_idx", pa.int64()),
        ("timestamp_us", pa.int64()),
        ("ego_to_world", vec(16)),  # row-major 4x4
    ],
)

TRACKS_SCHEMA = make_schema(
    "tracks",
    1,
    [
        ("seq_id", pa.string()),
        ("object_id", pa.string()),
        ("frame_idx", pa.int64()),
        ("category", pa.string()),
        ("center", vec(3)),
        ("size", vec(3)),  # length, width, height
        ("heading", pa.float32()),
        ("speed", pa.float32()),
        ("visible", pa.bool_()),
    ],
)

OBJECTS_SCHEMA = make_schema(
    "objects",
    1,
    [
        ("seq_id", pa.string()),
        ("object_id", pa.string()),
        ("category", pa.string()),
        ("node_type", pa.string()),  # "rigid" | "nonrigid" | "static"
        ("instance_id", pa.int32()),
        ("caption", pa.string()),
        ("attributes", pa.map_(pa.string(), pa.string())),
    ],
)

MAP_FEATURES_SCHEMA = make_schema(
    "map_features",
    1,
    [
        ("seq_id", pa.string()),
        ("feature_id", pa.string()),
        ("kind", pa.string()),
        ("points", pa.list_(vec(3))),  # [P, 3] world coordinates
    ],
)
