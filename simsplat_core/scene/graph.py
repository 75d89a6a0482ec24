"""``SceneGraph``: background + object nodes on a shared frame axis; ``at(t)`` composes world-space
Gaussians, ``render`` rasterizes them.

S(t) = {G_bg} ∪ {T_v(t) ⊗ G_v} (rigid) ∪ {T_h(t) ⊗ (G_h + offsets_h(t))} (non-rigid).

``at`` is a pure function of the parameters and ``t``: nothing is cached between calls. It is
vectorised over nodes: the poses of all object nodes are stacked ``[K, F, 4, 4]`` and gathered once per
call, then one batched transform moves every object Gaussian (the background block is passed through
untransformed). Only the per-node offset interpolation of non-rigid nodes loops (a handful of nodes),
as does the sampling of edited nodes that carry a pose track of their own.

**Any time.** ``t`` may lie outside the frame axis: log nodes follow their ``extrapolation`` policy
(``HOLD`` the first / last frame by default, or ``ABSENT``), nodes with their own
:class:`~simsplat_core.scene.pose_track.PoseTrack` follow that track and its policies (so an edited
agent can drive on past the log's last frame).

**By value.** A ``SceneGraph`` is frozen: ``to``, ``detached``, ``without``, ``with_node``,
``with_poses``, ``with_metadata`` and ``with_eps2d`` return new graphs that share the unchanged nodes
with the original, which is never changed. Each structural edit derives a new ``revision`` (a short
hash chain from the stored scene's ``""``), so data derived from a graph (``LanguageScene``'s node-id
maps) can tell which graph it was computed for.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import logging
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import Tensor

from simsplat_core.scene.composed import ComposedGaussians
from simsplat_core.scene.nodes import BACKGROUND_ID, BackgroundNode, NonRigidNode, ObjectNode, SceneNode
from simsplat_core.scene.pose_track import Extrapolation, FrameTime, PoseTrack, locate
from simsplat_core.scene.records import SceneRecords, graph_to_records, nodes_from_records
from simsplat_core.scene.render import DEFAULT_EPS2D, SceneRender, render_composed
from simsplat_core.scene.transforms import interpolate_transforms, quat_multiply, rotmat_to_quat, se3_delta

logger = logging.getLogger(__name__)

#: Records metadata key of ``SceneGraph.eps2d``.
EPS2D_KEY = "render_eps2d"


#: Records metadata key of ``SceneGraph.revision`` (written only for edited graphs).
REVISION_KEY = "graph_revision"


@dataclass(frozen=True, eq=False)
class SceneGraph:
    """A background node and object nodes (ids ``1..K``) over ``frame_indices [F]`` (sorted, int64).

    Attributes:
        frame_indices: log frame index of each position of the frame axis shared by all node poses.
        nodes: nodes ordered by ``node_id`` (background, id 0, first); stored as a tuple.
        metadata: free-form string facts (scene centre, scale, source sequence, ...); the graph keeps
            its own copy (derive changes with :meth:`with_metadata`).
        eps2d: the rasterizer's screen-space low-pass (pixels^2) the scene is rendered with; it is part of
            the model (Gaussians trained with one value look blurred or aliased with another) and is
            persisted in the records' metadata.
        revision: ``""`` for a reconstructed / stored scene; every structural edit (``without``,
            ``with_node``, ``with_poses``) derives a new one.
    """

    frame_indices: np.ndarray
    nodes: Sequence[SceneNode]
    metadata: dict[str, str] = field(default_factory=dict)
    eps2d: float = DEFAULT_EPS2D
    revision: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "frame_indices", np.asarray(self.frame_indices, dtype=np.int64))
        object.__setattr__(self, "nodes", tuple(self.nodes))
        object.__setattr__(self, "metadata", dict(self.metadata))
        if self.frame_indices.ndim != 1 or self.frame_indices.size == 0:
            raise ValueError("SceneGraph.frame_indices must be a non-empty [F] array")
        if np.any(np.diff(self.frame_indices) <= 0):
            raise ValueError("SceneGraph.frame_indices must be strictly increasing")
        ids = [n.node_id for n in self.nodes]
        if ids != sorted(ids) or len(set(ids)) != len(ids):
            raise ValueError(f"SceneGraph.nodes must be sorted by unique node_id, got {ids}")
        n_frames = self.frame_indices.size
        for node in self.nodes:
            if isinstance(node, ObjectNode) and node.present.shape[0] != n_frames:
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
    def object_nodes(self) -> list[ObjectNode]:
        return [n for n in self.nodes if isinstance(n, ObjectNode)]

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

    # ------------------------------------------------------------------ derived graphs (by value)
    def to(self, device: torch.device | str) -> SceneGraph:
        """A copy of the graph on ``device`` (this graph is not changed)."""
        return dataclasses.replace(self, nodes=tuple(n.to(device) for n in self.nodes))

    def detached(self) -> SceneGraph:
        """A graph whose learnable tensors are detached (no grad, no optimizer references)."""
        return dataclasses.replace(self, nodes=tuple(n.detached() for n in self.nodes))

    def with_metadata(self, **facts: str) -> SceneGraph:
        """A graph whose metadata has ``facts`` added (or replaced)."""
        return dataclasses.replace(self, metadata={**self.metadata, **{k: str(v) for k, v in facts.items()}})

    def with_eps2d(self, eps2d: float) -> SceneGraph:
        """A graph rendered with another screen-space low-pass."""
        return dataclasses.replace(self, eps2d=float(eps2d))

    def _check_ids(self, node_ids: Iterable[int], what: str) -> list[int]:
        ids = [int(i) for i in node_ids]
        known = {n.node_id for n in self.nodes}
        for nid in ids:
            if nid not in known:
                raise ValueError(f"SceneGraph.{what}: no node {nid} (nodes {sorted(known)})")
            if nid == BACKGROUND_ID and what != "without":
                raise ValueError(f"SceneGraph.{what}: node {nid} is the background, which has no poses")
        return ids

    def _derived(self, nodes: Iterable[SceneNode], *change: object) -> SceneGraph:
        digest = hashlib.sha1(repr((self.revision, *change)).encode()).hexdigest()[:16]
        return dataclasses.replace(self, nodes=tuple(sorted(nodes, key=lambda n: n.node_id)), revision=digest)

    def without(self, node_ids: Iterable[int]) -> SceneGraph:
        """The graph without the nodes ``node_ids`` (the others are shared, unchanged).

        Raises:
            ValueError: an id names no node (the message names it).
        """
        drop = set(self._check_ids(node_ids, "without"))
        return self._derived([n for n in self.nodes if n.node_id not in drop], "without", sorted(drop))

    def _axis_track(self, poses: PoseTrack | Tensor | np.ndarray, present: Tensor | np.ndarray | None,
                    node_id: int) -> tuple[PoseTrack | None, Tensor, Tensor]:
        """``(own track or None, poses [F, 4, 4], present [F])`` of a pose argument: ``[F, 4, 4]`` poses on
        the frame axis (with ``present [F]``, default all), or a :class:`PoseTrack` (resampled on the axis)."""
        device = self.device
        n_frames = self.frame_indices.size
        if isinstance(poses, PoseTrack):
            if present is not None:
                raise ValueError(f"node {node_id}: present comes with the PoseTrack, not separately")
            track = poses.to(device)
            on_axis = track.resampled(self.frame_indices.astype(np.float64))
            eye = torch.eye(4, device=device).expand(n_frames, 4, 4)
            axis_poses = torch.where(on_axis.mask[:, None, None], on_axis.poses, eye)
            return track, axis_poses.contiguous(), on_axis.mask
        axis_poses = torch.as_tensor(poses, dtype=torch.float32, device=device)
        if tuple(axis_poses.shape) != (n_frames, 4, 4):
            raise ValueError(f"node {node_id}: poses on the frame axis must be [F={n_frames}, 4, 4], "
                             f"got {list(axis_poses.shape)} (pass a PoseTrack for poses on other times)")
        mask = (torch.ones(n_frames, dtype=torch.bool, device=device) if present is None
                else torch.as_tensor(present, dtype=torch.bool, device=device))
        if tuple(mask.shape) != (n_frames,):
            raise ValueError(f"node {node_id}: present must be [F={n_frames}], got {list(mask.shape)}")
        return None, axis_poses, mask

    def with_node(self, node: ObjectNode, poses: PoseTrack | Tensor | np.ndarray | None = None,
                  present: Tensor | np.ndarray | None = None) -> SceneGraph:
        """The graph with ``node`` added (this graph is not changed).

        Args:
            node: an object node; ``node_id <= 0`` assigns the next free id (``max + 1``), any other id
                must be free.
            poses: the node's poses: ``[F, 4, 4]`` on the frame axis (with ``present [F]``), or a
                :class:`PoseTrack` on its own times (kept as the node's track, so it can run past the
                log's frames; resampled on the axis for records and training). ``None``: the node's
                own ``poses`` / ``present`` (which must be on the frame axis).

        Raises:
            ValueError: the id is taken, the node is a background, or the poses have the wrong shape.
        """
        if not isinstance(node, ObjectNode):
            raise ValueError(f"SceneGraph.with_node: node {node.node_id} is not an object node ({type(node).__name__})")
        taken = {n.node_id for n in self.nodes}
        node_id = node.node_id if node.node_id > 0 else max(taken) + 1
        if node_id in taken:
            raise ValueError(f"SceneGraph.with_node: node id {node_id} is taken")
        own_poses = poses is None  # the node's own poses keep their learned refinement; new ones are final
        if poses is None:
            poses, present = node.poses, node.present if present is None else present
        track, axis_poses, mask = self._axis_track(poses, present, node_id)
        new = dataclasses.replace(node.to(self.device), node_id=node_id, poses=axis_poses, present=mask,
                                  pose_deltas=node.pose_deltas if own_poses and track is None else None, track=track)
        return self._derived([*self.nodes, new], "with_node", node_id, _tensor_digest(new.poses, new.present),
                             _track_digest(track))

    def with_poses(self, node_id: int, poses: PoseTrack | Tensor | np.ndarray,
                   present: Tensor | np.ndarray | None = None) -> SceneGraph:
        """The graph with node ``node_id``'s pose track replaced (``poses`` as in :meth:`with_node`; the
        learned pose refinement is dropped: the new poses are final).

        Raises:
            ValueError: no such object node (named), or the poses have the wrong shape.
        """
        (nid,) = self._check_ids([node_id], "with_poses")
        old = self.node(nid)
        assert isinstance(old, ObjectNode)
        track, axis_poses, mask = self._axis_track(poses, present, nid)
        new = dataclasses.replace(old, poses=axis_poses, present=mask, pose_deltas=None, track=track)
        return self._derived([new if n.node_id == nid else n for n in self.nodes], "with_poses", nid,
                             _tensor_digest(axis_poses, mask), _track_digest(track))

    # ------------------------------------------------------------------ time
    def resolve_time(self, t: float) -> FrameTime:
        """Position of frame index ``t`` on the frame axis (clamped to its ends; ``side`` says when)."""
        return locate(self.frame_indices, t)

    def present_nodes(self, t: float) -> list[int]:
        """Ids of the nodes that exist at ``t`` (objects need a pose at both neighbouring frames)."""
        objs, _, alive = self.object_poses_at(t)
        alive_ids = {n.node_id for n, a in zip(objs, alive.tolist()) if a}
        return [n.node_id for n in self.nodes if not isinstance(n, ObjectNode) or n.node_id in alive_ids]

    def object_poses_at(self, t: float) -> tuple[list[ObjectNode], Tensor, Tensor]:
        """Poses of all object nodes at ``t``: ``(nodes, poses [K, 4, 4], present [K] bool)``.

        Poses are interpolated for fractional ``t`` and include the learned refinement (differentiable).
        Outside the frame axis each node's policy applies (module docstring); nodes with a track of
        their own are sampled on it.
        """
        ft = self.resolve_time(t)
        objs = self.object_nodes
        if not objs:
            eye = torch.eye(4, device=self.device)
            return objs, eye[:0], torch.zeros(0, dtype=torch.bool, device=self.device)
        poses = torch.stack([n.poses for n in objs])  # [K, F, 4, 4]
        present = torch.stack([n.present for n in objs])  # [K, F]
        alive = present[:, ft.i0] & present[:, ft.i1]
        if not ft.inside:
            absent = [n.extrapolation is Extrapolation.ABSENT for n in objs]
            if any(absent):
                alive = alive & ~torch.tensor(absent, device=alive.device)
        frames = [ft.i0] if ft.exact else [ft.i0, ft.i1]
        pose = poses[:, frames]  # [K, 1 or 2, 4, 4]
        if any(n.pose_deltas is not None for n in objs):
            deltas = torch.stack([n.pose_deltas if n.pose_deltas is not None
                                  else n.poses.new_zeros((n.poses.shape[0], 6)) for n in objs])  # [K, F, 6]
            pose = pose @ se3_delta(deltas[:, frames])  # refine at the frames, then interpolate
        pose = pose[:, 0] if ft.exact else interpolate_transforms(pose[:, 0], pose[:, 1], ft.w)
        own = [k for k, n in enumerate(objs) if n.track is not None]
        if own:  # edited nodes: sampled on their own track
            pose, alive = pose.clone(), alive.clone()
            for k in own:
                track = objs[k].track
                assert track is not None
                pose[k], alive[k] = track.sample(ft.t)
        return objs, pose, alive

    # ------------------------------------------------------------------ composition
    def at(self, t: float, *, exclude: Iterable[int] = (), holdout_offsets: bool = False) -> ComposedGaussians:
        """World-space Gaussians of every node present at ``t`` and not in ``exclude`` (node ids).

        Differentiable w.r.t. all node parameters. See the module docstring for the maths.
        ``holdout_offsets`` (training only) renders non-rigid nodes with offsets interpolated from the
        frames around ``t`` instead of those stored at ``t`` (``NonRigidNode.offsets_at``).
        """
        exclude = set(int(e) for e in exclude)
        objs, poses, _ = self.object_poses_at(t)
        alive_host = self._alive_host(t, objs)  # [K] bool, read from host mirrors (no device sync)
        device = self.device
        blocks: list[tuple[SceneNode, int]] = []  # (node, index into objs or -1)
        bg = self.background
        if bg is not None and BACKGROUND_ID not in exclude:
            blocks.append((bg, -1))
        for k, obj in enumerate(objs):
            if alive_host[k] and obj.node_id not in exclude:
                blocks.append((obj, k))
        if not blocks:
            return _empty_composed(float(t), device)

        counts = np.array([len(n.gaussians) for n, _ in blocks], dtype=np.int64)
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
        n_bg = int(counts[0]) if blocks[0][1] < 0 else 0
        obj_ks = np.array([k for _, k in blocks if k >= 0], dtype=np.int64)
        means = torch.cat(means_local)
        quats = torch.nn.functional.normalize(quats_local, dim=-1)
        if obj_ks.size:
            # row -> pose index built on the host and sent once (no repeat_interleave on device counts)
            obj_counts = counts[len(counts) - obj_ks.size:]
            used = poses if obj_ks.size == len(objs) else poses[torch.as_tensor(obj_ks, device=device)]
            local_idx = torch.as_tensor(np.repeat(np.arange(obj_ks.size), obj_counts), device=device)  # [M]
            rot = used[:, :3, :3]  # [K', 3, 3]
            q_pose = rotmat_to_quat(rot)  # [K', 4]
            m_obj = means[n_bg:]
            m_world = (rot[local_idx] @ m_obj[:, :, None])[:, :, 0] + used[local_idx, :3, 3]  # [M, 3]
            q_world = quat_multiply(q_pose[local_idx], quats[n_bg:])  # [M, 4]
            means = torch.cat([means[:n_bg], m_world]) if n_bg else m_world
            quats = torch.cat([quats[:n_bg], q_world]) if n_bg else q_world

        features = _compose_features([n for n, _ in blocks], counts.tolist(), device)
        node_id_host = np.array([n.node_id for n, _ in blocks], dtype=np.int32)
        offsets = self.node_offsets()
        canonical = np.concatenate([np.arange(*offsets[n.node_id], dtype=np.int64) for n, _ in blocks])
        starts = np.concatenate([[0], np.cumsum(counts)])
        slices = tuple((n.node_id, int(starts[i]), int(starts[i + 1])) for i, (n, _) in enumerate(blocks))
        return ComposedGaussians(
            t=float(t), means=means, quats=quats, scales=torch.exp(log_scales),
            opacities=torch.sigmoid(opacity_logits), colors=torch.sigmoid(colors), features=features,
            node_ids=torch.as_tensor(np.repeat(node_id_host, counts), device=device),
            gaussian_ids=torch.as_tensor(canonical, device=device), node_slices=slices,
        )

    def _alive_host(self, t: float, objs: Sequence[ObjectNode]) -> np.ndarray:
        """``[K]`` bool: which object nodes exist at ``t`` (as :meth:`object_poses_at`'s ``present``),
        from host mirrors of the presence masks so that composing never waits on the device. Nodes with
        a pose track of their own are asked on it (a host read: edited graphs only)."""
        ft = self.resolve_time(t)
        present = self._present_host  # [K, F]
        alive = present[:, ft.i0] & present[:, ft.i1] if len(objs) else np.zeros(0, dtype=bool)
        for k, n in enumerate(objs):
            if not ft.inside and n.extrapolation is Extrapolation.ABSENT:
                alive[k] = False
            if n.track is not None:
                alive[k] = n.track.sample(ft.t)[1]
        return alive

    @functools.cached_property
    def _present_host(self) -> np.ndarray:
        """``[K, F]`` bool host copy of the object nodes' presence masks (read once per graph: presence is
        part of the graph's structure, which only derived graphs change)."""
        objs = self.object_nodes
        if not objs:
            return np.zeros((0, self.frame_indices.size), dtype=bool)
        return torch.stack([n.present for n in objs]).cpu().numpy().astype(bool)

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
    def to_records(self, scene_id: str) -> SceneRecords:
        """Plain numpy/python records of the graph (see :mod:`simsplat_core.scene.records`)."""
        beyond = [n.node_id for n in self.object_nodes if n.track is not None
                  and (n.track.start < self.frame_indices[0] or n.track.end > self.frame_indices[-1])]
        if beyond:
            logger.warning("scene %s: nodes %s have pose tracks beyond the frame axis [%d, %d]; the records keep "
                           "their poses on the axis only", scene_id, beyond, self.frame_indices[0],
                           self.frame_indices[-1])
        records = graph_to_records(self, scene_id)
        records.metadata[EPS2D_KEY] = repr(float(self.eps2d))
        if self.revision:
            records.metadata[REVISION_KEY] = self.revision
        return records

    @classmethod
    def from_records(cls, records: SceneRecords, device: torch.device | str = "cpu") -> SceneGraph:
        """Inverse of :meth:`to_records` (learned pose refinements come back baked into the poses)."""
        frame_indices, nodes, metadata = nodes_from_records(records, device)
        eps2d = float(metadata.pop(EPS2D_KEY, DEFAULT_EPS2D))
        revision = metadata.pop(REVISION_KEY, "")
        return cls(frame_indices=frame_indices, nodes=nodes, metadata=metadata, eps2d=eps2d, revision=revision)


def _tensor_digest(*tensors: Tensor) -> str:
    h = hashlib.sha1()
    for t in tensors:
        h.update(t.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()[:16]


def _track_digest(track: PoseTrack | None) -> str:
    if track is None:
        return ""
    digest = _tensor_digest(torch.as_tensor(track.times), track.poses, track.mask)
    return f"{digest}:{track.before.value}:{track.after.value}"


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
