"""Schemas of a reconstructed scene's tables (``scenes/<seq_id>/<scene_hash>/``): Gaussians, nodes, node poses,
non-rigid deformations."""

from __future__ import annotations

import pyarrow as pa

from storage.schemas.base import make_schema, vec


# ----------------------------------------------------------------------------- scene tables
def gaussians_schema(feature_dim: int, color_dim: int = 3) -> pa.Schema:
    """One row per Gaussian; ``color[color_dim]`` (3 for RGB, 3*(deg+1)**2 for SH), ``feature[feature_dim]``.

    ``feature_dim == 0`` means the scene has no language features: the ``feature`` column is omitted.
    """
    if feature_dim < 0 or color_dim <= 0:
        raise ValueError(f"gaussians_schema: need feature_dim >= 0 and color_dim > 0, got {feature_dim}, {color_dim}")
    fields = [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("mean", vec(3)),
        ("log_scale", vec(3)),
        ("quat", vec(4)),  # w, x, y, z
        ("color", vec(color_dim)),
        ("opacity_logit", pa.float32()),
    ]
    if feature_dim:
        fields.append(("feature", vec(feature_dim)))
    return make_schema("gaussians", 1, fields, feature_dim=feature_dim, color_dim=color_dim)


def nodes_schema(dim: int) -> pa.Schema:
    """One row per scene-graph node; language features ``f_app``/``f_mot``/``f_loc`` of width ``dim``."""
    if dim <= 0:
        raise ValueError(f"nodes_schema: need dim > 0, got {dim}")
    return make_schema(
        "nodes",
        1,
        [
            ("scene_id", pa.string()),
            ("node_id", pa.int32()),
            ("node_type", pa.string()),  # "background" | "rigid" | "nonrigid" | "static"
            ("object_id", pa.string()),  # "" for the background node
            ("category", pa.string()),
            ("scale", pa.float32()),  # characteristic size in metres (scene radius, box half-diagonal)
            ("center", vec(3)),  # background: scene centre (world); objects: zeros
            ("f_app", vec(dim)),
            ("f_mot", vec(dim)),
            ("f_loc", vec(dim)),
        ],
        dim=dim,
    )


NODE_POSES_SCHEMA = make_schema(
    "node_poses",
    1,
    [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("frame_idx", pa.int64()),
        ("transform", vec(16)),  # row-major 4x4 node -> world
        ("deform_uri", pa.string()),  # non-rigid deformation artifact; "" for rigid nodes
    ],
)

DEFORMATIONS_SCHEMA = make_schema(
    "deformations",
    1,
    [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("frame_idx", pa.int64()),
        ("offsets", pa.list_(vec(3))),  # [N_h, 3] per-Gaussian offsets of a non-rigid node at this frame
    ],
)
