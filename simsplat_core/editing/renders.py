"""Render a scene graph at a log's frames from the log's cameras: colour, alpha and node ids.

    for frame in render_frames(edited.graph, log):          # one FrameRender per frame, cameras batched
        frame.rgb[c], frame.alpha[c], frame.node_id[c]       # camera c: [H, W, 3] / [H, W] / [H, W]

Each frame composes the graph's Gaussians once (``SceneGraph.at``) and rasterizes every camera of one
image size in one batch (``scene.render.render_composed``), with the exact per-pixel node ids of
``SceneRender.node_id`` composited in the same pass (``fused_ids``). Pure torch/numpy, no I/O.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.render import render_composed
from simsplat_core.scene_view import CameraView, reposed_cameras, shifted_cameras
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: ``progress(done, total)`` after each frame.
FrameProgress = Callable[[int, int], None]


@dataclass(frozen=True)
class FrameRender:
    """The renders of one frame.

    Attributes:
        frame_idx: the log frame.
        cameras: the ``C`` camera names, in the log's camera order.
        rgb: per camera ``[H, W, 3]`` float32 in ``[0, 1]``.
        alpha: per camera ``[H, W]`` float32 accumulated opacity.
        node_id: per camera ``[H, W]`` int32 node of largest compositing weight, ``-1`` where nothing opaque
            was hit (``None`` when not requested).
    """

    frame_idx: int
    cameras: tuple[str, ...]
    rgb: tuple[np.ndarray, ...]
    alpha: tuple[np.ndarray, ...]
    node_id: tuple[np.ndarray, ...] | None

    def camera(self, name: str) -> int:
        """Index of camera ``name``. Raises ``KeyError`` naming the cameras."""
        try:
            return self.cameras.index(name)
        except ValueError:
            raise KeyError(f"frame {self.frame_idx}: no camera {name!r}; cameras {list(self.cameras)}") from None


def frame_views(log: SceneLog, frame_idx: int, ego_to_world: np.ndarray | None = None) -> list[CameraView]:
    """The log's cameras at ``frame_idx`` (the order of the log's images); carried to ``ego_to_world [4, 4]``
    when the ego moves differently in the edit (refinement with ``ego_reacts``)."""
    if ego_to_world is None:
        return shifted_cameras(log, frame_idx)
    return reposed_cameras(log, frame_idx, ego_to_world)


@torch.no_grad()
def render_frame(graph: SceneGraph, frame_idx: int, views: Sequence[CameraView], *, with_node_ids: bool = True,
                 backend: str = "auto") -> FrameRender:
    """Render ``graph`` at ``frame_idx`` into ``views`` (composed once; views of one size in one batch)."""
    composed = graph.at(float(frame_idx))
    n = len(views)
    rgb: list[np.ndarray] = [np.zeros(0)] * n
    alpha: list[np.ndarray] = [np.zeros(0)] * n
    ids: list[np.ndarray] = [np.zeros(0)] * n
    for width, height in dict.fromkeys((v.width, v.height) for v in views):
        batch = [i for i, v in enumerate(views) if (v.width, v.height) == (width, height)]
        c2w = torch.tensor(np.stack([views[i].cam_to_world for i in batch]), dtype=torch.float32)  # [C, 4, 4]
        Ks = torch.tensor(np.stack([views[i].K for i in batch]), dtype=torch.float32)  # [C, 3, 3]
        out = render_composed(composed, c2w, Ks, width, height, with_node_ids=with_node_ids, backend=backend,
                              eps2d=graph.eps2d, fused_ids=True)
        for j, i in enumerate(batch):
            rgb[i] = out.rgb[j].cpu().numpy().astype(np.float32)
            alpha[i] = out.alpha[j, ..., 0].cpu().numpy().astype(np.float32)
            if out.node_id is not None:
                ids[i] = out.node_id[j].cpu().numpy().astype(np.int32)
    return FrameRender(frame_idx, tuple(v.camera for v in views), tuple(rgb), tuple(alpha),
                       tuple(ids) if with_node_ids else None)


def render_frames(graph: SceneGraph, log: SceneLog, frames: Sequence[int] | None = None, *,
                  with_node_ids: bool = True, backend: str = "auto",
                  progress: FrameProgress | None = None,
                  ego_poses: Mapping[int, np.ndarray] | None = None) -> Iterator[FrameRender]:
    """Render ``graph`` at each of ``frames`` (default: every log frame with camera images) from the log's
    cameras, one :class:`FrameRender` per frame, lazily; ``progress(done, total)`` after each. ``ego_poses``
    (frame -> ``[4, 4]``) carries the cameras of those frames to a moved ego."""
    if frames is None:
        frames = sorted({img.frame_idx for img in log.images})
    total = len(frames)
    for k, frame_idx in enumerate(frames):
        moved = ego_poses.get(int(frame_idx)) if ego_poses is not None else None
        yield render_frame(graph, int(frame_idx), frame_views(log, int(frame_idx), moved),
                           with_node_ids=with_node_ids, backend=backend)
        if progress is not None:
            progress(k + 1, total)
