"""Sampling a node's pose at any time: ``FrameTime`` on a time axis, ``Extrapolation`` policies, ``PoseTrack``.

A pose track is ``times [T]`` (frame indices, strictly increasing, fractional allowed), node->world
``poses [T, 4, 4]`` and ``present [T]`` (bool). At a time ``t``:

* between two samples the pose is interpolated (translation lerp, rotation nlerp,
  :func:`~simsplat_core.scene.transforms.interpolate_transforms`) and the node exists only when it is
  present at both neighbouring samples;
* on a sample, that sample;
* before the first / after the last sample, the track's :class:`Extrapolation` policy decides:
  ``HOLD`` keeps the first / last sample (pose and presence: an object that left before the end of
  the log stays absent), ``ABSENT`` removes the node.

The scene graph's log nodes use their pose rows on the graph's frame axis as such a track (policy
``ObjectNode.extrapolation``, ``HOLD`` by default); an edited node may carry a :class:`PoseTrack` of
its own (``SceneGraph.with_node`` / ``with_poses``), e.g. one that runs past the log's last frame.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from simsplat_core.scene.transforms import interpolate_transforms


class Extrapolation(enum.StrEnum):
    """What a pose track gives outside its time range."""

    HOLD = "hold"  #: the first (before) / last (after) sample, pose and presence
    ABSENT = "absent"  #: the node does not exist there


class OffsetExtrapolation(enum.StrEnum):
    """What a non-rigid node's deformation gives outside its trained frames."""

    HOLD = "hold"  #: the offsets of the first / last trained frame
    LOOP = "loop"  #: the trained frames repeat with period ``last - first`` (a walking cycle)


@dataclass(frozen=True)
class FrameTime:
    """A time ``t`` located on an axis ``times [T]``: ``t ~ (1 - w) times[i0] + w times[i1]``.

    ``side`` is ``-1`` before the first time, ``+1`` after the last (``i0 = i1`` is then the end
    sample and ``w = 0``), ``0`` inside.
    """

    t: float
    i0: int
    i1: int
    w: float
    side: int = 0

    @property
    def exact(self) -> bool:
        return self.w == 0.0

    @property
    def inside(self) -> bool:
        return self.side == 0


def locate(times: np.ndarray, t: float) -> FrameTime:
    """Position of ``t`` on the strictly increasing axis ``times [T]`` (clamped to its ends, see ``side``)."""
    t = float(t)
    if t < times[0]:
        return FrameTime(t, 0, 0, 0.0, -1)
    last = times.size - 1
    if t > times[last]:
        return FrameTime(t, last, last, 0.0, 1)
    i1 = int(np.searchsorted(times, t, side="left"))
    if times[i1] == t:
        return FrameTime(t, i1, i1, 0.0)
    i0 = i1 - 1
    return FrameTime(t, i0, i1, float((t - times[i0]) / (times[i1] - times[i0])))


def check_times(times: np.ndarray | list[float], what: str) -> np.ndarray:
    """``times`` as a float64 ``[T]`` array; raises ``ValueError`` (naming ``what``) unless non-empty and
    strictly increasing."""
    out = np.asarray(times, dtype=np.float64)
    if out.ndim != 1 or out.size == 0:
        raise ValueError(f"{what}: times must be a non-empty [T] array, got shape {list(out.shape)}")
    if np.any(np.diff(out) <= 0):
        raise ValueError(f"{what}: times must be strictly increasing")
    return out


@dataclass(frozen=True)
class PoseTrack:
    """A node->world pose track on its own time axis with explicit extrapolation (module docstring).

    Attributes:
        times: ``[T]`` float64 frame indices, strictly increasing (fractional allowed; may run past the
            log's last frame).
        poses: ``[T, 4, 4]`` float32 node->world transforms.
        present: ``[T]`` bool, true where the node exists (``None``: everywhere; stored as all true).
        before, after: policy before the first / after the last time.
    """

    times: np.ndarray
    poses: Tensor
    present: Tensor | None = None
    before: Extrapolation = Extrapolation.HOLD
    after: Extrapolation = Extrapolation.HOLD

    def __post_init__(self) -> None:
        times = check_times(self.times, "PoseTrack")
        poses = torch.as_tensor(self.poses, dtype=torch.float32)
        if tuple(poses.shape) != (times.size, 4, 4):
            raise ValueError(f"PoseTrack: poses must be [T={times.size}, 4, 4], got {list(poses.shape)}")
        present = (torch.ones(times.size, dtype=torch.bool, device=poses.device) if self.present is None
                   else torch.as_tensor(self.present, dtype=torch.bool, device=poses.device))
        if tuple(present.shape) != (times.size,):
            raise ValueError(f"PoseTrack: present must be [T={times.size}], got {list(present.shape)}")
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "poses", poses)
        object.__setattr__(self, "present", present)
        object.__setattr__(self, "before", Extrapolation(self.before))
        object.__setattr__(self, "after", Extrapolation(self.after))

    @property
    def mask(self) -> Tensor:
        """``[T]`` bool presence (``present`` after construction, never ``None``)."""
        return self.present  # type: ignore[return-value]  # __post_init__ fills it

    def __len__(self) -> int:
        return int(self.times.size)

    @property
    def start(self) -> float:
        return float(self.times[0])

    @property
    def end(self) -> float:
        return float(self.times[-1])

    def sample(self, t: float) -> tuple[Tensor, bool]:
        """``(pose [4, 4], present)`` at time ``t`` (the pose is the nearest sample's when absent)."""
        poses, present = self.sample_many(np.asarray([t], dtype=np.float64))
        return poses[0], bool(present[0])

    def sample_many(self, times: np.ndarray) -> tuple[Tensor, Tensor]:
        """``(poses [M, 4, 4], present [M] bool)`` at ``times [M]``."""
        located = [locate(self.times, float(t)) for t in np.asarray(times, dtype=np.float64).reshape(-1)]
        device = self.poses.device
        i0 = torch.as_tensor([ft.i0 for ft in located], dtype=torch.long, device=device)
        i1 = torch.as_tensor([ft.i1 for ft in located], dtype=torch.long, device=device)
        w = torch.as_tensor([ft.w for ft in located], dtype=self.poses.dtype, device=device)
        absent_before, absent_after = self.before is Extrapolation.ABSENT, self.after is Extrapolation.ABSENT
        outside_absent = torch.as_tensor([(ft.side < 0 and absent_before) or (ft.side > 0 and absent_after)
                                          for ft in located], dtype=torch.bool, device=device)
        present = self.mask[i0] & self.mask[i1] & ~outside_absent
        a, b = self.poses[i0], self.poses[i1]
        exact = w == 0
        poses = torch.where(exact[:, None, None], a, interpolate_transforms(a, b, w)) if len(located) else a
        return poses, present

    def resampled(self, times: np.ndarray) -> PoseTrack:
        """The track sampled at ``times [M]`` (same policies)."""
        times = check_times(times, "PoseTrack.resampled")
        poses, present = self.sample_many(times)
        return PoseTrack(times, poses, present, self.before, self.after)

    def with_policy(self, before: Extrapolation | None = None, after: Extrapolation | None = None) -> PoseTrack:
        """The same samples with other extrapolation policies (``None`` keeps one)."""
        return PoseTrack(self.times, self.poses, self.mask, before or self.before, after or self.after)

    def to(self, device: torch.device | str) -> PoseTrack:
        return PoseTrack(self.times, self.poses.to(device), self.mask.to(device), self.before, self.after)


__all__ = ["Extrapolation", "FrameTime", "OffsetExtrapolation", "PoseTrack", "check_times", "locate"]
