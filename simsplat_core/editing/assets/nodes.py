"""An asset on a pose track as a scene-graph node; a cut-out pedestrian's gait retimed to its new path.

    node = asset_node(asset, node_id=0, object_id="inserted_0", track=track, arc_length=s,
                      graph_frames=graph.frame_indices)
    edited = graph.with_node(node, poses=track)

Rigid assets become a :class:`RigidNode` (``static=True`` for static objects). A deformable asset (a
pedestrian cut out of a reconstruction, ``Asset.deformable``) becomes a :class:`NonRigidNode` whose
offsets are *retimed*: the gait phase follows the distance walked, not time.

**Gait retiming.** The source walked ``a_k`` metres up to its deform frame ``d_k`` (``k = 0 .. T_h-1``,
``Asset.deform_arc_length``). First a *loop* is chosen, the last deform frame ``d_L`` (at least half-way
along the walk) whose offsets and their change to the next frame are closest to the first frame's
(:func:`gait_loop`): ``[d_0, d_L]`` then holds whole gait cycles and repeats without a jump; its length
is ``W = a_L - a_0``. A new frame whose path has walked
``s`` metres (``arc_length``, from the start of the track) shows the source at the (fractional) deform
time ``tau`` with ``a(tau) = a_0 + (s mod W)``: a path twice as fast cycles the legs twice as fast, a
path longer than the source's walk loops. A source that did not walk (``W < STANDING_WALK_M``) loops in
time instead: ``tau = d_0 + (f - f_0) mod (d_L - d_0)``. The node gets offsets at every integer frame
from the first of ``graph_frames`` / the track to the last (``offsets_at`` interpolates in between).
"""

from __future__ import annotations

import logging
import math

import numpy as np
import torch

from simsplat_core.editing.assets.record import Asset
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.nodes import OFFSETS, NodeFields, NonRigidNode, ObjectNode, PoseFields, RigidNode
from simsplat_core.scene.pose_track import OffsetExtrapolation, PoseTrack

logger = logging.getLogger(__name__)

#: A source that walked less than this (metres) over its deform frames loops its deformation in time.
STANDING_WALK_M = 0.5
#: The gait loop ends at least this share of the way along the source's walk (or its frames).
MIN_LOOP_SHARE = 0.5
#: Loop ends within this factor of the best one's offset mismatch count as equally good (the latest wins).
LOOP_TOLERANCE = 1.25


def path_arc_length(track: PoseTrack) -> np.ndarray:
    """``[T]`` metres travelled along the track's ground positions (``xy`` of the poses), 0 at the first."""
    xy = track.poses[:, :2, 3].detach().cpu().double().numpy()
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1) if len(track) > 1 else np.zeros(0)
    return np.concatenate([[0.0], np.cumsum(steps)])


def gait_loop(offsets: torch.Tensor, frames: np.ndarray, arc: np.ndarray) -> int:
    """Index ``L`` of the deform frame that closes the gait loop (see the module docstring).

    A candidate ``k`` (at least ``MIN_LOOP_SHARE`` along the walk, or along the frames for a source that
    stood) is scored by how far frames ``k, k + 1`` are from frames ``0, 1`` (mean per-Gaussian distance):
    matching the pose *and* its motion, so half a cycle (legs together, moving the other way) does not
    close a loop. The latest candidate within ``LOOP_TOLERANCE`` of the best score wins.

    Args:
        offsets: ``[N, T_h, 3]`` per-Gaussian offsets.
        frames: ``[T_h]`` deform frames.
        arc: ``[T_h]`` metres walked up to each deform frame.
    Returns:
        ``L`` in ``[1, T_h - 1]`` (``0`` when there is a single frame).
    """
    n_frames = int(frames.size)
    if n_frames < 2:
        return 0
    walked = float(arc[-1] - arc[0])
    progress = (arc - arc[0]) / walked if walked >= STANDING_WALK_M else (frames - frames[0]) / float(
        frames[-1] - frames[0])
    candidates = np.flatnonzero(progress >= MIN_LOOP_SHARE)
    candidates = candidates[(candidates >= 1) & (candidates <= n_frames - 2)]
    if candidates.size == 0:
        return n_frames - 1

    def distance(k: int) -> float:
        return float(((offsets[:, k:k + 2] - offsets[:, 0:2]).norm(dim=-1)).mean())

    mismatch = np.array([distance(k) for k in candidates.tolist()])
    good = candidates[mismatch <= float(mismatch.min()) * LOOP_TOLERANCE + 1e-9]
    return int(good.max())


def source_deform_times(frames: np.ndarray, arc: np.ndarray, loop: int, new_frames: np.ndarray,
                        new_arc: np.ndarray) -> np.ndarray:
    """``[M]`` fractional source deform times shown at ``new_frames [M]`` (walked ``new_arc [M]`` metres).

    ``frames [T_h]`` / ``arc [T_h]`` are the source's deform frames and walked distances, ``loop`` the
    loop end (:func:`gait_loop`). See the module docstring for the rule.
    """
    frames = np.asarray(frames, dtype=np.float64)[: loop + 1]
    arc = np.asarray(arc, dtype=np.float64)[: loop + 1]
    new_frames = np.asarray(new_frames, dtype=np.float64)
    new_arc = np.asarray(new_arc, dtype=np.float64)
    walked = float(arc[-1] - arc[0])
    if frames.size < 2:
        return np.full(new_frames.shape, frames[0])
    if walked < STANDING_WALK_M:
        period = float(frames[-1] - frames[0])
        return frames[0] + np.mod(new_frames - new_frames[0], period)
    rel = arc - arc[0]
    keep = np.concatenate([[True], np.diff(rel) > 1e-6])  # strictly increasing support for the inverse
    target = np.mod(new_arc - new_arc[0], walked)
    return np.interp(target, rel[keep], frames[keep])


def _frame_range(track: PoseTrack, graph_frames: np.ndarray) -> np.ndarray:
    """``[M]`` integer frames from the first to the last of the graph's frames and the track's times."""
    first = math.floor(min(float(graph_frames[0]), track.start))
    last = math.ceil(max(float(graph_frames[-1]), track.end))
    return np.arange(first, last + 1, dtype=np.int64)


def retimed_offsets(asset: Asset, track: PoseTrack, arc_length: np.ndarray | None,
                    graph_frames: np.ndarray) -> tuple[np.ndarray, torch.Tensor]:
    """``(deform_frames [M], offsets [N, M, 3])`` of a deformable asset on a new path.

    Args:
        track: the new pose track (frame-index times).
        arc_length: ``[T]`` metres walked at ``track.times`` (``None``: from the track's positions).
        graph_frames: ``[F]`` the graph's frame axis.

    Raises:
        ValueError: the asset is rigid, or ``arc_length`` does not match the track.
    """
    if asset.deform_frames is None or asset.deform_arc_length is None or asset.offsets is None:
        raise ValueError(f"asset {asset.asset_id!r} has no deformation to retime")
    s = path_arc_length(track) if arc_length is None else np.asarray(arc_length, dtype=np.float64).reshape(-1)
    if s.shape != (len(track),):
        raise ValueError(f"arc_length must be [T={len(track)}] like the track's times, got {list(s.shape)}")
    if np.any(np.diff(s) < -1e-6):
        raise ValueError("arc_length must be non-decreasing (metres walked from the start of the track)")
    new_frames = _frame_range(track, np.asarray(graph_frames))
    new_arc = np.interp(new_frames.astype(np.float64), track.times, s)  # held before / after the track
    source = _nonrigid(NodeFields(node_id=1, gaussians=asset.gaussians, object_id=asset.source_object,
                                  category=asset.category, scale=asset.half_diagonal), asset.deform_frames)
    loop = gait_loop(asset.offsets, asset.deform_frames, asset.deform_arc_length)
    taus = source_deform_times(asset.deform_frames, asset.deform_arc_length, loop, new_frames, new_arc)
    offsets = torch.stack([source.offsets_at(float(tau)) for tau in taus], dim=1)  # [N, M, 3]
    logger.debug("asset %s: gait loop %d frames (%.2f m); %d new frames over %.1f m", asset.asset_id, loop + 1,
                 asset.deform_arc_length[loop] - asset.deform_arc_length[0], new_frames.size, new_arc[-1] - new_arc[0])
    return new_frames, offsets


def _with_offsets(gs: GaussianSet, offsets: torch.Tensor) -> GaussianSet:
    """``gs`` (tensors shared) with ``extras["offsets"]`` replaced by ``offsets [N, M, 3]``."""
    return GaussianSet(gs.means, gs.log_scales, gs.quats, gs.colors, gs.opacity_logits, gs.features,
                       {**gs.extras, OFFSETS: offsets})


def _nonrigid(common: NodeFields, frames: np.ndarray, poses: PoseFields | None = None,
              track: PoseTrack | None = None) -> NonRigidNode:
    pose_kw = poses or PoseFields(poses=torch.eye(4)[None], present=torch.ones(1, dtype=torch.bool))
    return NonRigidNode(**common, **pose_kw, track=track, deform_frames=frames,
                        offset_extrapolation=OffsetExtrapolation.HOLD)


def asset_node(asset: Asset, *, node_id: int, object_id: str, track: PoseTrack, arc_length: np.ndarray | None,
               graph_frames: np.ndarray) -> ObjectNode:
    """The scene-graph node of ``asset`` driving ``track`` (see the module docstring).

    The node's ``poses`` / ``present`` are the track sampled on ``graph_frames`` and its own ``track`` is
    set, so it can be used as it is; ``SceneGraph.with_node(node, poses=track)`` adds it to a graph
    (``node_id <= 0`` lets the graph pick the next free id).

    Args:
        asset: what to insert.
        node_id, object_id: the new node's ids.
        track: node->world box poses over frame-index times (box centre ``h / 2`` above the ground).
        arc_length: ``[T]`` metres travelled at ``track.times`` (retimes a pedestrian's gait; ``None``:
            measured on the track).
        graph_frames: ``[F]`` the graph's frame axis.
    """
    graph_frames = np.asarray(graph_frames, dtype=np.int64)
    on_axis = track.resampled(graph_frames.astype(np.float64))
    eye = torch.eye(4).expand(graph_frames.size, 4, 4)
    pose_kw = PoseFields(poses=torch.where(on_axis.mask[:, None, None], on_axis.poses, eye).contiguous(),
                         present=on_axis.mask.clone())
    common = NodeFields(node_id=int(node_id), gaussians=asset.gaussians, object_id=object_id,
                        category=asset.category, scale=asset.half_diagonal)
    if asset.deformable:
        frames, offsets = retimed_offsets(asset, track, arc_length, graph_frames)
        common["gaussians"] = _with_offsets(asset.gaussians, offsets)
        return _nonrigid(common, frames, pose_kw, track)
    return RigidNode(**common, **pose_kw, track=track, static=asset.category == "static")


__all__ = ["LOOP_TOLERANCE", "MIN_LOOP_SHARE", "STANDING_WALK_M", "asset_node", "gait_loop", "path_arc_length",
           "retimed_offsets", "source_deform_times"]
