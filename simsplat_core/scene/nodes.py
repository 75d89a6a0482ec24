"""Scene-graph nodes: the static background, rigid objects (vehicles; static objects with a constant
pose) and non-rigid objects (pedestrians with a learned per-frame deformation). Rigid and non-rigid
nodes share the pose-carrying base :class:`ObjectNode`; a non-rigid node is not a rigid one.

Every node owns one :class:`GaussianSet` in its own frame. Object nodes carry their node->world pose
on the graph's frame axis (``SceneGraph.frame_indices``, ``F`` entries):

* ``poses [F, 4, 4]`` float32 node->world (box frame: origin at the box centre, x along the heading,
  z up); rows where the object is absent are the identity and ``present [F]`` is false there;
* ``pose_deltas [F, 6]`` (optional, learnable pose refinement): the pose used at frame ``f`` is
  ``poses[f] @ se3_delta(pose_deltas[f])`` (translation + axis-angle in the box frame); between frames
  the refined poses are interpolated. ``None`` (the default) means the track poses are used as they are.

A :class:`NonRigidNode` additionally holds ``offsets [N, T_h, 3]`` (in its Gaussians' ``extras``, so
densification keeps it row-aligned): per-Gaussian displacements in the box frame at the
``deform_frames [T_h]`` frame indices it was trained on, linearly interpolated between them (clamped
outside, or looped: ``offset_extrapolation``). Nodes are plain parameter holders: every function of
time lives in ``SceneGraph.at``. ``to`` / ``detached`` return new nodes; only a trainer mutates the
nodes of the graph it owns.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TypedDict

import numpy as np
import torch
from torch import Tensor

from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.pose_track import Extrapolation, OffsetExtrapolation, PoseTrack
from simsplat_core.scene.transforms import se3_delta

#: Node types as stored in records (``nodes.node_type``).
NODE_TYPES: tuple[str, ...] = ("background", "rigid", "nonrigid", "static")
BACKGROUND_ID = 0
OFFSETS = "offsets"


class NodeFields(TypedDict):
    """Keyword arguments of the fields every node has (``SceneNode``), for building nodes of any type."""

    node_id: int
    gaussians: GaussianSet
    object_id: str
    category: str
    scale: float


class PoseFields(TypedDict):
    """Keyword arguments of an object node's poses on the frame axis (``ObjectNode.poses`` / ``present``)."""

    poses: Tensor
    present: Tensor


@dataclass
class SceneNode:
    """Base of all nodes: an id, descriptive fields and the node's Gaussians.

    ``scale`` is the node's characteristic size in metres (scene radius for the background, box
    half-diagonal for objects): learning rates of means and densification thresholds are relative to it.
    """

    node_id: int
    gaussians: GaussianSet
    object_id: str = ""
    category: str = ""
    scale: float = 1.0

    @property
    def node_type(self) -> str:
        raise NotImplementedError

    def tensors(self) -> dict[str, Tensor]:
        """Learnable tensors of the node by name (Gaussian rows and node-level parameters)."""
        return dict(self.gaussians.named_tensors())

    def to(self, device: torch.device | str) -> SceneNode:
        """A copy of the node on ``device`` (the node itself is not changed)."""
        return dataclasses.replace(self, gaussians=self.gaussians.to(device))

    def detached(self) -> SceneNode:
        """A copy whose learnable tensors are detached (no grad, no optimizer references)."""
        return dataclasses.replace(self, gaussians=self.gaussians.detach())


@dataclass
class BackgroundNode(SceneNode):
    """Static world-space Gaussians (road, buildings, the sky dome). Always present, identity pose.

    ``center`` is the scene centre (mean training camera position) the background ``scale`` refers to.
    """

    center: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def node_type(self) -> str:
        return "background"


@dataclass
class ObjectNode(SceneNode):
    """Base of the pose-carrying object nodes (:class:`RigidNode`, :class:`NonRigidNode`).

    ``poses [F, 4, 4]`` / ``present [F]`` / ``pose_deltas [F, 6]`` are on the graph's frame axis (module
    docstring). ``extrapolation`` is the policy of that track before the first / after the last frame
    (``HOLD``: the first / last frame's pose and presence). ``track`` (optional) is a pose track of the
    node's own (e.g. an edited trajectory that runs past the log's last frame): when set, the node's
    pose at any time comes from it and ``poses`` / ``present`` are its samples on the frame axis (what
    records, training and renders on the axis use); ``pose_deltas`` must then be ``None``. Build such
    nodes with ``SceneGraph.with_node`` / ``with_poses``, which keep the two consistent.
    """

    poses: Tensor = field(default_factory=lambda: torch.eye(4)[None])  # [F, 4, 4]
    present: Tensor = field(default_factory=lambda: torch.ones(1, dtype=torch.bool))  # [F]
    pose_deltas: Tensor | None = None  # [F, 6]
    track: PoseTrack | None = None
    extrapolation: Extrapolation = Extrapolation.HOLD

    def __post_init__(self) -> None:
        n_frames = self.present.shape[0]
        if tuple(self.poses.shape) != (n_frames, 4, 4):
            raise ValueError(f"node {self.node_id}: poses must be [F={n_frames}, 4, 4], got {list(self.poses.shape)}")
        if self.pose_deltas is not None and tuple(self.pose_deltas.shape) != (n_frames, 6):
            raise ValueError(f"node {self.node_id}: pose_deltas must be [F={n_frames}, 6], "
                             f"got {list(self.pose_deltas.shape)}")
        if self.track is not None and self.pose_deltas is not None:
            raise ValueError(f"node {self.node_id}: a node with its own pose track has no pose_deltas")
        self.extrapolation = Extrapolation(self.extrapolation)

    @property
    def node_type(self) -> str:
        raise NotImplementedError

    def tensors(self) -> dict[str, Tensor]:
        out = super().tensors()
        if self.pose_deltas is not None:
            out["pose_deltas"] = self.pose_deltas
        return out

    def refined_poses(self) -> Tensor:
        """``[F, 4, 4]`` poses with the learned refinement applied (detached)."""
        with torch.no_grad():
            if self.pose_deltas is None:
                return self.poses.clone()
            return self.poses @ se3_delta(self.pose_deltas)

    def to(self, device: torch.device | str) -> ObjectNode:
        return dataclasses.replace(
            self, gaussians=self.gaussians.to(device), poses=self.poses.to(device), present=self.present.to(device),
            pose_deltas=None if self.pose_deltas is None else self.pose_deltas.detach().to(device),
            track=None if self.track is None else self.track.to(device))

    def detached(self) -> ObjectNode:
        return dataclasses.replace(
            self, gaussians=self.gaussians.detach(),
            pose_deltas=None if self.pose_deltas is None else self.pose_deltas.detach())


@dataclass
class RigidNode(ObjectNode):
    """An object moved rigidly by its per-frame box pose (``static=True``: node type ``"static"``)."""

    static: bool = False

    @property
    def node_type(self) -> str:
        return "static" if self.static else "rigid"


@dataclass
class NonRigidNode(ObjectNode):
    """A deformable object: rigid box pose plus per-frame per-Gaussian offsets (``extras["offsets"]``).

    ``offset_extrapolation`` is what the offsets do outside ``deform_frames`` (``HOLD``: the first /
    last trained frame's offsets; ``LOOP``: the trained frames repeat).
    """

    deform_frames: np.ndarray = field(default_factory=lambda: np.zeros(1, dtype=np.int64))  # [T_h]
    offset_extrapolation: OffsetExtrapolation = OffsetExtrapolation.HOLD

    def __post_init__(self) -> None:
        super().__post_init__()
        self.offset_extrapolation = OffsetExtrapolation(self.offset_extrapolation)
        self.deform_frames = np.asarray(self.deform_frames, dtype=np.int64)
        if self.deform_frames.ndim != 1 or self.deform_frames.size == 0:
            raise ValueError(f"node {self.node_id}: deform_frames must be a non-empty [T] array")
        if np.any(np.diff(self.deform_frames) <= 0):
            raise ValueError(f"node {self.node_id}: deform_frames must be strictly increasing")
        offsets = self.gaussians.extras.get(OFFSETS)
        expected = (len(self.gaussians), int(self.deform_frames.size), 3)
        if offsets is None or tuple(offsets.shape) != expected:
            got = None if offsets is None else list(offsets.shape)
            raise ValueError(f"node {self.node_id}: gaussians.extras['offsets'] must be {list(expected)}, got {got}")

    @property
    def node_type(self) -> str:
        return "nonrigid"

    @property
    def offsets(self) -> Tensor:
        """``[N, T_h, 3]`` per-Gaussian offsets at ``deform_frames``."""
        return self.gaussians.extras[OFFSETS]

    def _deform_time(self, t: float) -> float:
        """``t`` mapped into the trained range by ``offset_extrapolation`` (``LOOP`` only; ``HOLD`` clamps
        in :meth:`offsets_at`)."""
        first, last = float(self.deform_frames[0]), float(self.deform_frames[-1])
        if self.offset_extrapolation is OffsetExtrapolation.LOOP and last > first and not first <= t <= last:
            return first + (t - first) % (last - first)
        return t

    def offsets_at(self, t: float, holdout: bool = False) -> Tensor:
        """``[N, 3]`` offsets at (fractional) frame index ``t``: linear between the two neighbouring
        ``deform_frames``; outside their range as ``offset_extrapolation`` says (held by default).

        ``holdout=True`` ignores the offsets stored at ``t`` itself (if any) and interpolates between
        the neighbouring frames instead: training with it teaches the offsets to interpolate, which is
        how held-out frames are rendered.
        """
        frames = self.deform_frames
        offsets = self.offsets
        t = self._deform_time(float(t))
        if holdout and frames.size > 2:
            keep = frames != t
            if not keep.all():
                idx = np.flatnonzero(keep)
                frames, offsets = frames[idx], offsets[:, torch.as_tensor(idx, device=offsets.device)]
        j1 = int(np.searchsorted(frames, t, side="left"))
        if j1 < frames.size and frames[j1] == t:
            return offsets[:, j1]
        if j1 == 0:
            return offsets[:, 0]
        if j1 >= frames.size:
            return offsets[:, -1]
        j0 = j1 - 1
        w = float((t - frames[j0]) / (frames[j1] - frames[j0]))
        return (1.0 - w) * offsets[:, j0] + w * offsets[:, j1]


__all__ = ["BACKGROUND_ID", "NODE_TYPES", "OFFSETS", "BackgroundNode", "NodeFields", "NonRigidNode", "ObjectNode",
           "PoseFields", "RigidNode", "SceneNode"]
