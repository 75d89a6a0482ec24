"""``SceneGraph``: background + object nodes on a shared frame axis; ``at(t)`` composes world-space
Gaussians, ``render`` rasterizes them.

S(t) = {G_bg} ∪ {T_v(t) ⊗ G_v} (rigid) ∪ {T_h(t) ⊗ (G_h + offsets_h(t))} (non-rigid).

``at`` is a pure function of the parameters and ``t``: nothing is cached between calls. It is
vectorised over nodes: the poses of all object nodes are stacked ``[K, F, 4, 4]`` and gathered once per
call, then one batched transform moves every object Gaussian (the background block is passed through
untransformed). Only the per-node offset interpolation of non-rigid nodes loops (a handful of nodes).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Iterable

import numpy as np
import torch
from torch import Tensor

from simsplat_core.scene.composed import ComposedGaussians
from simsplat_core.scene.nodes import BACKGROUND_ID, BackgroundNode, NonRigidNode, RigidNode, SceneNode
from simsplat_core.scene.render import DEFAULT_EPS2D, SceneRender, render_composed
from simsplat_core.scene.transforms import interpolate_transforms, quat_multiply, rotmat_to_quat, se3_delta

if TYPE_CHECKING:
    from simsplat_core.scene.records import SceneRecords

logger = logging.getLogger(__name__)

#: Records metadata key of ``SceneGraph.eps2d``.
EPS2D_KEY = "render_eps2d"


@dataclass(frozen=True)
class FrameTime:
    """A (fractional) frame index resolved on the graph's frame axis: ``t = (1 - w) f[i0] + w f[i1]``."""

    t: float
    i0: int
    i1: int
    w: float

    @property
    def exact(self) -> bool:
        return self.w == 0.0


@dataclass
class SceneGraph:
    """A background node and object nodes (ids ``1..K``) over ``frame_indices [F]`` (sorted, int64).

    Attributes:
        frame_indices: log frame index of each position of the frame axis shared by all node poses.
        nodes: node list ordered by ``node_id`` (background, id 0, first).
        metadata: free-form string facts (scene centre, scale, source sequence, ...).
        eps2d: the rasterizer's screen-space low-pass (pixels^2) the scene is rendered with; it is part of
            the model (Gaussians trained with one value look blurred or aliased with another) and is
            persisted in the records' metadata.
    """

    frame_indices: np.ndarray
    nodes: list[SceneNode]
    metadata: dict[str, str] = field(default_factory=dict)
    eps2d: float = DEFAULT_EPS2D

    def __post_init__(self) -> None:
        self.frame_indices = np.asarray(self.frame_indices, dtype=np.int64)
        if self.frame_indices.ndim != 1 or self.frame_indices.size == 0:
            raise ValueError("SceneGraph.frame_indices must be a non-empty [F] array")
        if np.any(np.diff(self.frame_indices) <= 0):
            raise ValueError("SceneGraph.frame_indices must be strictly increasing")
        ids = [n.node_id for n in self.nodes]
        if ids != sorted(ids) or len(set(ids)) != len(ids):
            raise ValueError(f"SceneGraph.nodes must be sorted by unique node_id, got {ids}")
        n_frames = self.frame_indices.size
        for node in self.nodes:
            if isinstance(node, RigidNode) and node.present.shape[0] != n_frames:
                raise ValueError(f"node {node.node_id}: present has {node.present.shape[0]} frames, "
                                 f"the graph has {n_frames}")

    # ------------------------------------------------------------------ lookup
    def node(self, node_id: int) -> SceneNode:
        for n in self.nodes:
            if n.node_id == node_id:
                return n
        raise KeyError(f"no node {node_id}")

    @property
    def background(self) -> BackgroundNode | None:
        first = self.nodes[0] if self.nodes else None
        return first if isinstance(first, BackgroundNode) else None

    @property
    def object_nodes(self) -> list[RigidNode]:
        return [n for n in self.nodes if isinstance(n, RigidNode)]

    @property
    def num_gaussians(self) -> int:
        return sum(len(n.gaussians) for n in self.nodes)

    @property
    def device(self) -> torch.device:
        return self.nodes[0].gaussians.means.device

    def node_offsets(self) -> dict[int, tuple[int, int]]:
        """``node_id -> (start, stop)`` rows of each node in the canonical concatenation (node order)."""
        out, start = {}, 0
        for n in self.nodes:
            out[n.node_id] = (start, start + len(n.gaussians))
            start += len(n.gaussians)
        return out

    def to(self, device: torch.device | str) -> "SceneGraph":
        for n in self.nodes:
            n.to(device)
        return self

    # ------------------------------------------------------------------ time
    def resolve_time(self, t: float) -> FrameTime:
        """Position of frame index ``t`` on the frame axis; raises outside ``[first, last]``."""
        frames = self.frame_indices
        t = float(t)
        if not frames[0] <= t <= frames[-1]:
            raise ValueError(f"t={t} is outside the graph's frames [{frames[0]}, {frames[-1]}]")
        i1 = int(np.searchsorted(frames, t, side="left"))
        if frames[i1] == t:
            return FrameTime(t, i1, i1, 0.0)
        i0 = i1 - 1
        return FrameTime(t, i0, i1, float((t - frames[i0]) / (frames[i1] - frames[i0])))

    def present_nodes(self, t: float) -> list[int]:
        """Ids of the nodes that exist at ``t`` (objects need a pose at both neighbouring frames)."""
        ft = self.resolve_time(t)
        out = []
        for n in self.nodes:
            if isinstance(n, RigidNode):
                if not bool(n.present[ft.i0]) or not bool(n.present[ft.i1]):
                    continue
            out.append(n.node_id)
        return out

    def object_poses_at(self, t: float) -> tuple[list[RigidNode], Tensor, Tensor]:
        """Poses of all object nodes at ``t``: ``(nodes, poses [K, 4, 4], present [K] bool)``.

        Poses are interpolated for fractional ``t`` and include the learned refinement (differentiable).
        """
        ft = self.resolve_time(t)
        objs = self.object_nodes
        if not objs:
            eye = torch.eye(4, device=self.device)
            return objs, eye[:0], torch.zeros(0, dtype=torch.bool, device=self.device)
        poses = torch.stack([n.poses for n in objs])  # [K, F, 4, 4]
        present = torch.stack([n.present for n in objs])  # [K, F]
        alive = present[:, ft.i0] & present[:, ft.i1]
        frames = [ft.i0] if ft.exact else [ft.i0, ft.i1]
        pose = poses[:, frames]  # [K, 1 or 2, 4, 4]
        if any(n.pose_deltas is not None for n in objs):
            deltas = torch.stack([n.pose_deltas if n.pose_deltas is not None
                                  else n.poses.new_zeros((n.poses.shape[0], 6)) for n in objs])  # [K, F, 6]
            pose = pose @ se3_delta(deltas[:, frames])  # refine at the frames, then interpolate
        if ft.exact:
            return objs, pose[:, 0], alive
        return objs, interpolate_transforms(pose[:, 0], pose[:, 1], ft.w), alive

    # ------------------------------------------------------------------ composition
    def at(self, t: float, *, exclude: Iterable[int] = (), holdout_offsets: bool = False) -> ComposedGaussians:
        """World-space Gaussians of every node present at ``t`` and not in ``exclude`` (node ids).

        Differentiable w.r.t. all node parameters. See the module docstring for the maths.
        ``holdout_offsets`` (training only) renders non-rigid nodes with offsets interpolated from the
        frames around ``t`` instead of those stored at ``t`` (``NonRigidNode.offsets_at``).
        """
        exclude = set(int(e) for e in exclude)
        objs, poses, alive = self.object_poses_at(t)
        offsets = self.node_offsets()
        device = self.device
        blocks: list[tuple[SceneNode, int]] = []  # (node, index into objs or -1)
        bg = self.background
        if bg is not None and BACKGROUND_ID not in exclude:
            blocks.append((bg, -1))
        alive_list = alive.tolist()
        for k, n in enumerate(objs):
            if alive_list[k] and n.node_id not in exclude:
                blocks.append((n, k))
        if not blocks:
            return _empty_composed(float(t), device)

        counts = [len(n.gaussians) for n, _ in blocks]
        means_local = []
        for n, _ in blocks:
            m = n.gaussians.means
            if isinstance(n, NonRigidNode):
                m = m + n.offsets_at(float(t), holdout=holdout_offsets)
            means_local.append(m)
        quats_local = torch.cat([n.gaussians.quats for n, _ in blocks])
        log_scales = torch.cat([n.gaussians.log_scales for n, _ in blocks])
        colors = torch.cat([n.gaussians.colors for n, _ in blocks])
        opacity_logits = torch.cat([n.gaussians.opacity_logits for n, _ in blocks])

        # batched rigid transform of the object blocks (background block stays in world coordinates)
        n_bg = counts[0] if blocks[0][1] < 0 else 0
        obj_blocks = [(n, k) for n, k in blocks if k >= 0]
        means = torch.cat(means_local)
        quats = torch.nn.functional.normalize(quats_local, dim=-1)
        if obj_blocks:
            obj_counts = torch.tensor([len(n.gaussians) for n, _ in obj_blocks], device=device)
            pose_idx = torch.repeat_interleave(torch.tensor([k for _, k in obj_blocks], device=device), obj_counts)
            rot = poses[:, :3, :3]  # [K, 3, 3]
            trans = poses[:, :3, 3]  # [K, 3]
            q_pose = rotmat_to_quat(rot)  # [K, 4]
            m_obj = means[n_bg:]
            m_world = torch.einsum("nij,nj->ni", rot[pose_idx], m_obj) + trans[pose_idx]  # [M, 3]
            q_world = quat_multiply(q_pose[pose_idx], quats[n_bg:])  # [M, 4]
            means = torch.cat([means[:n_bg], m_world])
            quats = torch.cat([quats[:n_bg], q_world])

        features = _compose_features([n for n, _ in blocks], counts, device)
        node_ids = torch.repeat_interleave(
            torch.tensor([n.node_id for n, _ in blocks], dtype=torch.int32, device=device),
            torch.tensor(counts, device=device))
        gaussian_ids = torch.cat([torch.arange(offsets[n.node_id][0], offsets[n.node_id][1], device=device)
                                  for n, _ in blocks])
        starts = np.concatenate([[0], np.cumsum(counts)])
        slices = tuple((n.node_id, int(starts[i]), int(starts[i + 1])) for i, (n, _) in enumerate(blocks))
        return ComposedGaussians(
            t=float(t), means=means, quats=quats, scales=torch.exp(log_scales),
            opacities=torch.sigmoid(opacity_logits), colors=torch.sigmoid(colors), features=features,
            node_ids=node_ids, gaussian_ids=gaussian_ids, node_slices=slices,
        )

    def render(
        self,
        t: float,
        cam_to_world: Tensor | np.ndarray,  # [C, 4, 4]
        Ks: Tensor | np.ndarray,  # [C, 3, 3]
        width: int,
        height: int,
        *,
        with_node_ids: bool = True,
        backend: str = "auto",
        exclude: Iterable[int] = (),
        background: Tensor | None = None,
    ) -> SceneRender:
        """Render the scene at ``t`` into ``C`` OpenCV cameras (see :class:`SceneRender`).

        Runs with autograd when the caller has it enabled; wrap in ``torch.no_grad()`` for inference.
        """
        composed = self.at(t, exclude=exclude)
        return render_composed(composed, torch.as_tensor(cam_to_world), torch.as_tensor(Ks), width, height,
                               with_node_ids=with_node_ids, backend=backend, background=background, eps2d=self.eps2d)

    # ------------------------------------------------------------------ persistence
    def to_records(self, scene_id: str) -> "SceneRecords":
        """Plain numpy/python records of the graph (see :mod:`simsplat_core.scene.records`)."""
        from simsplat_core.scene.records import graph_to_records

        records = graph_to_records(self, scene_id)
        records.metadata[EPS2D_KEY] = repr(float(self.eps2d))
        return records

    @classmethod
    def from_records(cls, records: "SceneRecords", device: torch.device | str = "cpu") -> "SceneGraph":
        """Inverse of :meth:`to_records` (learned pose refinements come back baked into the poses)."""
        from simsplat_core.scene.records import nodes_from_records

        frame_indices, nodes, metadata = nodes_from_records(records, device)
        eps2d = float(metadata.pop(EPS2D_KEY, DEFAULT_EPS2D))
        return cls(frame_indices=frame_indices, nodes=nodes, metadata=metadata, eps2d=eps2d)


def _compose_features(nodes: list[SceneNode], counts: list[int], device: torch.device) -> Tensor | None:
    dims = {n.gaussians.features.shape[1] for n in nodes if n.gaussians.features is not None}
    if not dims:
        return None
    if len(dims) > 1:
        raise ValueError(f"nodes have features of different widths {sorted(dims)}")
    d = dims.pop()
    parts = [n.gaussians.features if n.gaussians.features is not None
             else torch.zeros((c, d), dtype=n.gaussians.means.dtype, device=device) for n, c in zip(nodes, counts)]
    return torch.cat(parts)


def _empty_composed(t: float, device: torch.device) -> ComposedGaussians:
    z = lambda *s: torch.zeros(s, device=device)  # noqa: E731
    return ComposedGaussians(t, z(0, 3), z(0, 4), z(0, 3), z(0), z(0, 3), None,
                             torch.zeros(0, dtype=torch.int32, device=device),
                             torch.zeros(0, dtype=torch.int64, device=device), ())
