"""Camera views of a ``SceneLog`` grouped for rendering: all images of one frame with the same size and split.

The rasterizer renders a batch of cameras of one size in one call, so a frame whose cameras differ in
size (real logs) yields one :class:`ViewBatch` per size; a frame whose held-out view is one camera (DGP)
yields a train batch and a test batch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import DTypeLike
from torch import Tensor

from simsplat_core.types import CameraImage, SceneLog


@dataclass(frozen=True)
class ViewBatch:
    """``C`` cameras of one frame with the same image size.

    Attributes:
        frame_idx, split: the frame and its split (``"train"`` / ``"test"``).
        cameras: camera names ``[C]``.
        cam_to_world: ``[C, 4, 4]`` float32 OpenCV camera->world.
        Ks: ``[C, 3, 3]`` float32 intrinsics.
        width, height: image size.
        rgb: ``[C, H, W, 3]`` float32 ground truth in ``[0, 1]`` or ``None``.
        depth: ``[C, H, W]`` float32 z-depth (``inf`` = nothing hit) or ``None``.
        instance: ``[C, H, W]`` int32 instance ids (0 = background) or ``None``.
        valid: ``[C, H, W]`` bool, ``True`` where pixels count (``CameraImage.valid_mask``), or ``None`` when
            every pixel does.
    """

    frame_idx: int
    split: str
    cameras: tuple[str, ...]
    cam_to_world: Tensor
    Ks: Tensor
    width: int
    height: int
    rgb: Tensor | None
    depth: Tensor | None
    instance: Tensor | None
    valid: Tensor | None = None

    @property
    def num_cameras(self) -> int:
        return len(self.cameras)

    def subset(self, index: list[int]) -> ViewBatch:
        """The cameras at positions ``index``."""
        pick = lambda t: None if t is None else t[index]  # noqa: E731
        return ViewBatch(self.frame_idx, self.split, tuple(self.cameras[i] for i in index), self.cam_to_world[index],
                         self.Ks[index], self.width, self.height, pick(self.rgb), pick(self.depth),
                         pick(self.instance), pick(self.valid))

    def to(self, device: torch.device | str) -> ViewBatch:
        mv = lambda t: None if t is None else t.to(device)  # noqa: E731
        return ViewBatch(self.frame_idx, self.split, self.cameras, self.cam_to_world.to(device), self.Ks.to(device),
                         self.width, self.height, mv(self.rgb), mv(self.depth), mv(self.instance),
                         mv(self.valid))


def _stack(images: list[CameraImage], attr: str, dtype: DTypeLike) -> Tensor | None:
    arrays = [getattr(img, attr) for img in images]
    if any(a is None for a in arrays):
        return None
    return torch.from_numpy(np.stack([np.asarray(a, dtype=dtype) for a in arrays]))


def _stack_valid(images: list[CameraImage]) -> Tensor | None:
    """``[C, H, W]`` bool validity of ``images`` (all-true for an image without a mask), ``None`` without masks."""
    if all(img.valid_mask is None for img in images):
        return None
    return torch.from_numpy(np.stack([
        np.ones((img.height, img.width), bool) if img.valid_mask is None else np.asarray(img.valid_mask, bool)
        for img in images]))


def view_batches(log: SceneLog, split: str | None = None) -> list[ViewBatch]:
    """Every (frame, image size, split) group of ``log``'s images, frame-major, cameras in first-seen order.

    ``split`` keeps only frames of that split (``None``: all).
    """
    groups: dict[tuple[int, int, int, str], list[CameraImage]] = {}
    for img in log.images:
        if split is not None and img.split != split:
            continue
        groups.setdefault((img.frame_idx, img.width, img.height, img.split), []).append(img)
    out = []
    for (frame, width, height, image_split), images in sorted(groups.items()):
        out.append(ViewBatch(
            frame_idx=frame, split=image_split, cameras=tuple(img.camera for img in images),
            cam_to_world=torch.from_numpy(np.stack([img.cam_to_world for img in images]).astype(np.float32)),
            Ks=torch.from_numpy(np.stack([img.K for img in images]).astype(np.float32)),
            width=width, height=height, rgb=_stack(images, "image", np.float32),
            depth=_stack(images, "depth", np.float32), instance=_stack(images, "instance", np.int32),
            valid=_stack_valid(images),
        ))
    return out
