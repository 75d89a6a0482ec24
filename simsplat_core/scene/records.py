"""``SceneRecords``: a scene graph as plain numpy/python data, ready for the Parquet tables of DESIGN.md
(``gaussians``, ``nodes``, ``node_poses``) plus the non-rigid deformation arrays. No torch in the records.

Column conventions:

* ``gaussians``: ``node_id int32 [N]``, ``mean float32 [N, 3]`` (node frame), ``log_scale float32 [N, 3]``,
  ``quat float32 [N, 4]`` (w, x, y, z, unnormalised as trained), ``color float32 [N, 3]`` (activated RGB
  in ``[0, 1]``), ``opacity_logit float32 [N]`` and, when the graph has features, ``feature float32 [N, d]``.
  Rows are grouped by node in node order; inside a node they keep the node's order.
* ``nodes``: one dict per node ``{node_id, node_type, object_id ("" for the background), category}`` plus
  ``scale`` (metres, the node's characteristic size) and, for the background, ``center`` ``[3]``.
* ``node_poses``: ``node_id int32 [M]``, ``frame_idx int64 [M]``, ``transform float32 [M, 16]`` (row-major
  node->world, identity for the background), one row per (node, frame where the node exists); learned
  pose refinements are baked in.
* ``deformations[node_id]``: ``float32 [T, N_h, 3]`` offsets of a non-rigid node's Gaussians (node
  frame), at the frame indices ``deformation_frames[node_id]`` (``int64 [T]``).
* ``frame_indices``: ``int64 [F]`` the graph's frame axis; ``scene_id``; ``metadata`` string facts.

A graph rebuilt with ``SceneGraph.from_records`` renders identically (colours go through
``logit(sigmoid(x))``, exact to float32 rounding).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from simsplat_core.scene.gaussians import GaussianSet, logit
from simsplat_core.scene.nodes import (
    BACKGROUND_ID,
    NODE_TYPES,
    OFFSETS,
    BackgroundNode,
    NodeFields,
    NonRigidNode,
    ObjectNode,
    PoseFields,
    RigidNode,
    SceneNode,
)

GAUSSIAN_COLUMNS: tuple[str, ...] = ("node_id", "mean", "log_scale", "quat", "color", "opacity_logit")
POSE_COLUMNS: tuple[str, ...] = ("node_id", "frame_idx", "transform")


@dataclass
class SceneRecords:
    """Plain-data form of a :class:`~simsplat_core.scene.SceneGraph` (see the module docstring)."""

    scene_id: str
    frame_indices: np.ndarray
    gaussians: dict[str, np.ndarray]
    nodes: list[dict[str, Any]]
    node_poses: dict[str, np.ndarray]
    deformations: dict[int, np.ndarray] = field(default_factory=dict)
    deformation_frames: dict[int, np.ndarray] = field(default_factory=dict)
    metadata: dict[str, str] = field(default_factory=dict)

    @property
    def num_gaussians(self) -> int:
        return int(self.gaussians["node_id"].shape[0])

    def validate(self) -> SceneRecords:
        """Check column presence, dtypes' widths and cross references; raises ``ValueError``."""
        n = self.num_gaussians
        widths = {"mean": 3, "log_scale": 3, "quat": 4, "color": 3}
        for name in GAUSSIAN_COLUMNS:
            if name not in self.gaussians:
                raise ValueError(f"SceneRecords.gaussians: missing column {name!r}")
            col = self.gaussians[name]
            if col.shape[0] != n:
                raise ValueError(f"SceneRecords.gaussians[{name!r}]: {col.shape[0]} rows, expected {n}")
            if name in widths and col.shape[1:] != (widths[name],):
                raise ValueError(f"SceneRecords.gaussians[{name!r}]: shape {col.shape}, expected [N, {widths[name]}]")
        m = self.node_poses["node_id"].shape[0] if "node_id" in self.node_poses else 0
        for name in POSE_COLUMNS:
            if name not in self.node_poses or self.node_poses[name].shape[0] != m:
                raise ValueError(f"SceneRecords.node_poses: column {name!r} missing or not {m} rows")
        if self.node_poses["transform"].shape[1:] != (16,):
            raise ValueError("SceneRecords.node_poses['transform'] must be [M, 16]")
        node_ids = {int(d["node_id"]) for d in self.nodes}
        for d in self.nodes:
            if d["node_type"] not in NODE_TYPES:
                raise ValueError(f"SceneRecords.nodes: node {d['node_id']} has unknown node_type {d['node_type']!r}")
        unknown = set(np.unique(self.gaussians["node_id"]).tolist()) - node_ids
        if unknown:
            raise ValueError(f"SceneRecords.gaussians: node ids {sorted(unknown)} not in nodes")
        for nid, arr in self.deformations.items():
            frames = self.deformation_frames.get(nid)
            n_h = int((self.gaussians["node_id"] == nid).sum())
            if frames is None or arr.shape != (frames.shape[0], n_h, 3):
                raise ValueError(f"SceneRecords.deformations[{nid}]: shape {arr.shape} does not match "
                                 f"{None if frames is None else frames.shape[0]} frames x {n_h} Gaussians x 3")
        return self


def _np32(t: torch.Tensor) -> np.ndarray:
    return np.ascontiguousarray(t.detach().cpu().numpy().astype(np.float32))


def graph_to_records(graph: Any, scene_id: str) -> SceneRecords:
    """Records of a ``SceneGraph`` (typed ``Any`` to keep this module below ``graph`` in the imports)."""
    frames = np.asarray(graph.frame_indices, dtype=np.int64)
    cols: dict[str, list[np.ndarray]] = {name: [] for name in GAUSSIAN_COLUMNS}
    feats: list[np.ndarray | None] = []
    pose_ids, pose_frames, pose_tf = [], [], []
    nodes, deformations, deformation_frames = [], {}, {}
    for node in graph.nodes:
        g = node.gaussians
        n = len(g)
        cols["node_id"].append(np.full(n, node.node_id, dtype=np.int32))
        cols["mean"].append(_np32(g.means))
        cols["log_scale"].append(_np32(g.log_scales))
        cols["quat"].append(_np32(g.quats))
        cols["color"].append(_np32(torch.sigmoid(g.colors)))
        cols["opacity_logit"].append(_np32(g.opacity_logits))
        feats.append(None if g.features is None else _np32(g.features))
        info = {"node_id": int(node.node_id), "node_type": node.node_type, "object_id": node.object_id,
                "category": node.category, "scale": float(node.scale)}
        if isinstance(node, BackgroundNode):
            info["center"] = [float(c) for c in node.center]
        nodes.append(info)
        if isinstance(node, ObjectNode):
            present = node.present.detach().cpu().numpy().astype(bool)
            tf = node.refined_poses().detach().cpu().numpy().astype(np.float32).reshape(-1, 16)
            pose_ids.append(np.full(int(present.sum()), node.node_id, dtype=np.int32))
            pose_frames.append(frames[present])
            pose_tf.append(tf[present])
        else:
            pose_ids.append(np.full(frames.size, node.node_id, dtype=np.int32))
            pose_frames.append(frames.copy())
            pose_tf.append(np.tile(np.eye(4, dtype=np.float32).reshape(1, 16), (frames.size, 1)))
        if isinstance(node, NonRigidNode):
            deformations[node.node_id] = np.ascontiguousarray(_np32(node.offsets).transpose(1, 0, 2))
            deformation_frames[node.node_id] = node.deform_frames.copy()
    gaussians = {name: np.concatenate(parts) for name, parts in cols.items()}
    widths = {f.shape[1] for f in feats if f is not None}
    if widths:
        d = widths.pop()
        gaussians["feature"] = np.concatenate([
            f if f is not None else np.zeros((c.shape[0], d), np.float32) for f, c in zip(feats, cols["node_id"])])
    node_poses: dict[str, np.ndarray] = {
        "node_id": np.concatenate(pose_ids) if pose_ids else np.zeros(0, np.int32),
        "frame_idx": np.concatenate(pose_frames).astype(np.int64) if pose_frames else np.zeros(0, np.int64),
        "transform": np.concatenate(pose_tf) if pose_tf else np.zeros((0, 16), np.float32),
    }
    return SceneRecords(scene_id=scene_id, frame_indices=frames, gaussians=gaussians, nodes=nodes,
                        node_poses=node_poses, deformations=deformations, deformation_frames=deformation_frames,
                        metadata=dict(graph.metadata)).validate()


def nodes_from_records(records: SceneRecords, device: torch.device | str = "cpu"
                       ) -> tuple[np.ndarray, list[SceneNode], dict[str, str]]:
    """``(frame_indices, nodes, metadata)`` rebuilt from records (inverse of :func:`graph_to_records`)."""
    records.validate()
    frames = np.asarray(records.frame_indices, dtype=np.int64)
    n_frames = frames.size
    t = lambda a: torch.as_tensor(np.ascontiguousarray(a), dtype=torch.float32, device=device)  # noqa: E731
    g_ids = records.gaussians["node_id"]
    p_ids = records.node_poses["node_id"]
    nodes: list[SceneNode] = []
    for info in sorted(records.nodes, key=lambda d: int(d["node_id"])):
        nid, kind = int(info["node_id"]), info["node_type"]
        rows = g_ids == nid
        extras = {}
        if kind == "nonrigid":
            extras[OFFSETS] = t(np.asarray(records.deformations[nid]).transpose(1, 0, 2))
        feature = records.gaussians.get("feature")
        gs = GaussianSet(
            means=t(records.gaussians["mean"][rows]), log_scales=t(records.gaussians["log_scale"][rows]),
            quats=t(records.gaussians["quat"][rows]), colors=logit(t(records.gaussians["color"][rows])),
            opacity_logits=t(records.gaussians["opacity_logit"][rows]),
            features=None if feature is None else t(feature[rows]), extras=extras,
        )
        common = NodeFields(node_id=nid, gaussians=gs, object_id=str(info.get("object_id", "")),
                            category=str(info.get("category", "")), scale=float(info.get("scale", 1.0)))
        if kind == "background":
            if nid != BACKGROUND_ID:
                raise ValueError(f"SceneRecords.nodes: background node must have id {BACKGROUND_ID}, got {nid}")
            center = [float(c) for c in info.get("center", (0.0, 0.0, 0.0))]
            if len(center) != 3:
                raise ValueError(f"SceneRecords.nodes: background center must have 3 values, got {center}")
            nodes.append(BackgroundNode(**common, center=(center[0], center[1], center[2])))
            continue
        prow = p_ids == nid
        pose_frames = records.node_poses["frame_idx"][prow]
        pos = np.searchsorted(frames, pose_frames)
        if np.any(pos >= n_frames) or np.any(frames[np.minimum(pos, n_frames - 1)] != pose_frames):
            raise ValueError(f"SceneRecords.node_poses: node {nid} has frames outside frame_indices")
        poses = np.tile(np.eye(4, dtype=np.float32), (n_frames, 1, 1))
        poses[pos] = records.node_poses["transform"][prow].reshape(-1, 4, 4)
        present = np.zeros(n_frames, dtype=bool)
        present[pos] = True
        pose_kw = PoseFields(poses=t(poses), present=torch.as_tensor(present, device=device))
        if kind == "nonrigid":
            nodes.append(NonRigidNode(**common, **pose_kw, deform_frames=records.deformation_frames[nid]))
        else:
            nodes.append(RigidNode(**common, **pose_kw, static=kind == "static"))
    return frames, nodes, dict(records.metadata)
