"""What the mining loop shows a VLM: small renders of the stored scene to propose from, and of an edited scene --
a few telling frames, the bird's-eye view and the targets' visible pixels -- to judge.

    views = proposal_views(ctx.graph, ctx.log, max_width=320)        # [H, W, 3] uint8 per camera, first frame
    shown = judge_views(edited, ctx.log, frames=3, max_width=320)    # JudgeViews
    request = judge_request_from_edit(edited, shown.renders, shown.bev, visible_pixels=shown.visible_pixels)

Telling frames: ``frames`` steps spread over the steps where a target of the edit exists (``judge_input.targets_of``;
a removed target: where the log had it), each rendered from every camera (carried to the ego's edited poses when
it reacts, as ``editing.renders.frame_views`` does) at most ``max_width`` pixels wide, and shown in the camera
where the targets cover most pixels (the first camera when none shows them). The targets' pixels are counted in
the shown renders, from the renderer's node ids. The BEV is ``viz.bev.edit_bev``, what ``simsplat edit`` writes
as ``bev.png``.

A log without cameras (a motion-forecasting scenario: nothing to render) is shown by its bird's-eye view alone: the
proposal view is the log's BEV, the judge's one "render" is the edit's BEV and the targets' pixels are not measured
(``visible_pixels`` ``None``): the judge decides from the trajectories.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.renders import frame_views, render_frame
from simsplat_core.editing.result import EditedScene
from simsplat_core.mining.judge_input import targets_of, visible_pixels_of
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene_view import CameraView
from simsplat_core.types import SceneLog
from simsplat_core.viz.before_after import sample_steps
from simsplat_core.viz.bev import edit_bev
from simsplat_core.viz.images import to_uint8

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class JudgeViews:
    """The pictures of one edit for the judge.

    Attributes:
        renders: ``R`` images ``[h, w, 3]`` uint8, one per telling frame (in time order).
        frames: the ``R`` log frames shown; cameras: the camera of each.
        bev: ``[S, S, 3]`` uint8 bird's-eye view of the edit.
        visible_pixels: target object id -> pixels it covers in ``renders`` (``None``: a log without cameras).
    """

    renders: tuple[np.ndarray, ...]
    frames: tuple[int, ...]
    cameras: tuple[str, ...]
    bev: np.ndarray
    visible_pixels: dict[str, int] | None


def scaled_views(views: Sequence[CameraView], max_width: int) -> list[CameraView]:
    """``views`` shrunk to at most ``max_width`` pixels wide (intrinsics scaled alike; never enlarged)."""
    out = []
    for v in views:
        scale = min(1.0, max_width / v.width)
        if scale == 1.0:
            out.append(v)
            continue
        K = np.array(v.K, dtype=np.float64, copy=True)
        K[:2] *= scale
        out.append(CameraView(v.camera, K, v.cam_to_world, max(1, round(v.width * scale)),
                              max(1, round(v.height * scale))))
    return out


def image_frames(log: SceneLog) -> list[int]:
    """The log frames that have camera images (calibration), ascending."""
    return sorted({img.frame_idx for img in log.images})


def proposal_views(graph: SceneGraph, log: SceneLog, *, frame_idx: int | None = None, max_width: int = 320,
                   states: AgentStates | None = None) -> list[np.ndarray]:
    """Every camera's render of ``graph`` at ``frame_idx`` (default: the first frame with images), ``[h, w, 3]``
    uint8 each, at most ``max_width`` wide; for a log without cameras the bird's-eye view of ``states`` (the log's
    agents), ``max_width`` square.

    Raises:
        ValueError: the log has no camera images and no ``states`` are given.
    """
    frames = image_frames(log)
    if not frames:
        if states is None:
            raise ValueError(f"{log.seq_id}: the log has no cameras to render views from")
        return [edit_bev(log.map_features, states, states, size=max_width)]
    frame = frames[0] if frame_idx is None else int(frame_idx)
    rendered = render_frame(graph, frame, scaled_views(frame_views(log, frame), max_width), with_node_ids=False)
    return [to_uint8(np.clip(rgb, 0.0, 1.0)) for rgb in rendered.rgb]


def target_steps(edited: EditedScene) -> np.ndarray:
    """``[T]`` bool: steps where a target of the edit exists (in the edit, or in the log for a removed one)."""
    states, before = edited.states, edited.original_states
    active = np.zeros(states.num_steps, bool)
    for oid in dict.fromkeys(o for ids in targets_of(edited) for o in ids):
        if oid in states.object_ids:
            active |= states.valid[states.index(oid)]
        elif oid in before.object_ids:
            active |= before.valid[before.index(oid)]
    return active


def telling_frames(edited: EditedScene, log: SceneLog, count: int) -> list[int]:
    """Up to ``count`` distinct log frames with images spread over :func:`target_steps` (module docstring)."""
    have = np.asarray(image_frames(log))
    if have.size == 0:
        return []
    picked = [int(edited.states.frame_idx[s]) for s in sample_steps(target_steps(edited), count)]
    nearest = [int(have[np.argmin(np.abs(have - f))]) for f in picked]
    return list(dict.fromkeys(nearest))


def judge_views(edited: EditedScene, log: SceneLog, *, frames: int = 3, max_width: int = 320, bev_size: int = 320,
                title: str = "") -> JudgeViews:
    """The renders, BEV and target pixels of ``edited`` (module docstring; a log without cameras: the BEV alone);
    ``title`` is drawn on the BEV."""
    shown = telling_frames(edited, log, frames)
    if not shown:
        bev = edit_bev(log.map_features, edited.original_states, edited.states, title=title, size=bev_size)
        return JudgeViews((bev,), (), ("bev",), bev, None)
    targets = [o for ids in targets_of(edited) for o in ids if o in edited.states.object_ids]
    nodes = np.asarray([edited.states.node_ids[edited.states.index(o)] for o in targets], np.int64)
    moved = edited.ego_poses(log.ego_poses)
    renders, cameras, id_maps = [], [], []
    for frame in shown:
        views = scaled_views(frame_views(log, frame, moved.get(frame)), max_width)
        rendered = render_frame(edited.graph, frame, views)
        assert rendered.node_id is not None
        pixels = [int(np.isin(ids, nodes[nodes >= 0]).sum()) for ids in rendered.node_id]
        best = int(np.argmax(pixels))  # the first camera on ties (and when no camera shows a target)
        renders.append(to_uint8(np.clip(rendered.rgb[best], 0.0, 1.0)))
        cameras.append(rendered.cameras[best])
        id_maps.append(rendered.node_id[best])
    visible = visible_pixels_of(id_maps, edited.states, targets)
    bev = edit_bev(log.map_features, edited.original_states, edited.states, title=title, size=bev_size)
    logger.debug("%s: judge views at frames %s (%s); target pixels %s", log.seq_id, shown, cameras, visible)
    return JudgeViews(tuple(renders), tuple(shown), tuple(cameras), bev, visible)


__all__ = ["JudgeViews", "image_frames", "judge_views", "proposal_views", "scaled_views", "target_steps",
           "telling_frames"]
