"""Schemas of editing: the asset bank, the run's ``edits`` table, edited trajectories and pose tracks."""

from __future__ import annotations

import pyarrow as pa

from storage.schemas.base import make_schema, vec

# ----------------------------------------------------------------------------- asset bank
ASSETS_SCHEMA = make_schema(
    "assets",
    1,
    [
        ("bank_hash", pa.string()),
        ("asset_id", pa.string()),
        ("category", pa.string()),  # "vehicle" | "pedestrian" | "static"
        ("subtype", pa.string()),
        ("caption", pa.string()),
        ("color", pa.string()),
        ("size", vec(3)),  # box length, width, height (metres)
        ("source_seq", pa.string()),  # "" for procedural assets
        ("source_object", pa.string()),  # "" for procedural assets
        ("num_gaussians", pa.int64()),
        ("gaussians_uri", pa.string()),  # gaussians/<asset_id>.parquet, relative to the bank directory
        ("deform_uri", pa.string()),  # deform/<asset_id>.parquet for deformable assets, else ""
        ("deform_frames", pa.list_(pa.int64())),  # [T_h] source frames of the offsets (empty when rigid)
        ("deform_arc_length", pa.list_(pa.float32())),  # [T_h] metres walked up to each (empty when rigid)
        ("attributes", pa.map_(pa.string(), pa.string())),
    ],
)

# ----------------------------------------------------------------------------- run tables
#: Mining columns of the ``edits`` table (version 2, ``judge_reasons`` since version 3; null in rows of
#: ``simsplat edit`` and in files written before them).
EDITS_MINING_COLUMNS: tuple[str, ...] = (
    "mining_status", "scenario", "source", "category", "follows_prompt", "plausibility", "adjustment", "export",
    "client", "seconds_propose", "seconds_command", "seconds_edit", "seconds_render", "seconds_judge",
    "judge_reasons",
)

EDITS_SCHEMA = make_schema(
    "edits",
    3,  # 2: mining columns (nullable); 3: judge_reasons (nullable)
    [
        ("run_id", pa.string()),
        ("seq_id", pa.string()),
        ("edit_id", pa.string()),
        ("attempt", pa.int32()),
        ("prompt", pa.string()),
        ("command_json", pa.string()),
        ("status", pa.string()),
        ("failure_reason", pa.string()),  # "" when the attempt succeeded
        ("mining_status", pa.string()),  # "accepted" | "rejected" | "refused" | "failed" (mining.attempts)
        ("scenario", pa.int32()),  # index of the mined proposal in its sequence
        ("source", pa.string()),  # "seed" | "client"
        ("category", pa.string()),  # one of the six edit categories ("" when unknown)
        ("follows_prompt", pa.bool_()),  # the judge's answers (null when not judged)
        ("plausibility", pa.int32()),
        ("adjustment", pa.string()),  # what changed from the previous attempt
        ("export", pa.bool_()),  # an accepted scenario marked for export (false for a plain `simsplat edit`)
        ("client", pa.string()),  # the VLM client's name
        ("seconds_propose", pa.float64()),
        ("seconds_command", pa.float64()),
        ("seconds_edit", pa.float64()),
        ("seconds_render", pa.float64()),
        ("seconds_judge", pa.float64()),
        ("judge_reasons", pa.string()),  # the judge's reasons as a JSON list of strings (null when not judged)
    ],
    nullable=EDITS_MINING_COLUMNS,
)

#: Box columns of the ``trajectories`` table (version 3; null in version-2 files).
TRAJECTORY_BOX_COLUMNS: tuple[str, ...] = ("z", "length", "width", "height")

TRAJECTORIES_SCHEMA = make_schema(
    "trajectories",
    3,  # 2: category column, source "inserted"; 3: box centre height and size (nullable)
    [
        ("edit_id", pa.string()),
        ("object_id", pa.string()),  # the log's id for existing agents ("ego" for the ego), a new one when inserted
        ("category", pa.string()),
        ("step", pa.int32()),  # the log's frame index
        ("x", pa.float32()),
        ("y", pa.float32()),
        ("heading", pa.float32()),
        ("speed", pa.float32()),  # signed, m/s (negative when reversing)
        ("source", pa.string()),  # "log" | "edited" | "inserted" | "refined"
        ("z", pa.float32()),  # box centre height, metres (world frame)
        ("length", pa.float32()),  # box size, metres
        ("width", pa.float32()),
        ("height", pa.float32()),
    ],
    nullable=TRAJECTORY_BOX_COLUMNS,
)

EDIT_POSE_TRACKS_SCHEMA = make_schema(
    "edit_pose_tracks",
    1,
    [
        ("node_id", pa.int32()),  # the node the track belongs to (added or re-tracked)
        ("t", pa.float64()),  # fractional frame index of the sample (may run past the log's frames)
        ("transform", vec(16)),  # row-major 4x4 node -> world
        ("present", pa.bool_()),
        ("arc_length", pa.float64()),  # metres along the new path (NaN: none; retimes a pedestrian's gait)
    ],
)
