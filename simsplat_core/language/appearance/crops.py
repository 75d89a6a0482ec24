"""Per-object image crops: the unit every appearance source consumes.

An ``ObjectCrop`` is one object seen by one camera in one frame: the pixels of the mask's bounding
box (plus a margin) and the mask itself. The mask may come from a log's instance ids (the synthetic
world's ground truth, ``crops_from_log``) or from projecting a scene-graph node's Gaussians.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class ObjectCrop:
    """One object in one camera image.

    Attributes:
        rgb: ``[h, w, 3]`` float32 display RGB in ``[0, 1]`` (the crop, not the full image).
        mask: ``[h, w]`` bool, the object's pixels within the crop.
        category: object category (``types.CATEGORIES``).
        box_size: ``[3]`` float64 box ``(length, width, height)`` in metres.
        frame_idx: frame of the image.
        camera: camera name.
        object_id: the object (scene-graph node) the mask belongs to.
        bbox: ``(x0, y0, x1, y1)`` of the crop in the full image (pixels, end-exclusive).
    """

    rgb: np.ndarray
    mask: np.ndarray
    category: str
    box_size: np.ndarray
    frame_idx: int
    camera: str
    object_id: str
    bbox: tuple[int, int, int, int] = (0, 0, 0, 0)

    def __post_init__(self) -> None:
        if self.rgb.ndim != 3 or self.rgb.shape[2] != 3:
            raise ValueError(f"crop of {self.object_id!r}: rgb must be [h, w, 3], got {self.rgb.shape}")
        if self.mask.shape != self.rgb.shape[:2]:
            raise ValueError(f"crop of {self.object_id!r}: mask {self.mask.shape} does not match rgb {self.rgb.shape}")

    @property
    def area(self) -> int:
        """Number of mask pixels."""
        return int(np.count_nonzero(self.mask))


def crop_object(
    image: np.ndarray,
    mask: np.ndarray,
    margin: int = 2,
) -> tuple[np.ndarray, np.ndarray, tuple[int, int, int, int]] | None:
    """Cut the bounding box of ``mask [H, W]`` (grown by ``margin`` pixels) out of ``image [H, W, 3]``.

    Returns:
        ``(rgb [h, w, 3] float32, mask [h, w] bool, (x0, y0, x1, y1))``, or ``None`` for an empty mask.
    """
    rows = np.nonzero(mask.any(axis=1))[0]
    cols = np.nonzero(mask.any(axis=0))[0]
    if rows.size == 0:
        return None
    height, width = mask.shape
    y0, y1 = max(int(rows[0]) - margin, 0), min(int(rows[-1]) + 1 + margin, height)
    x0, x1 = max(int(cols[0]) - margin, 0), min(int(cols[-1]) + 1 + margin, width)
    rgb = np.ascontiguousarray(image[y0:y1, x0:x1], dtype=np.float32)
    return rgb, np.ascontiguousarray(mask[y0:y1, x0:x1], dtype=bool), (x0, y0, x1, y1)


def crops_from_log(
    log: SceneLog,
    min_area: int = 100,
    object_ids: Iterable[str] | None = None,
    frames: Iterable[int] | None = None,
    margin: int = 2,
) -> list[ObjectCrop]:
    """Crops of every object in every image of ``log`` that has pixels and instance masks.

    Args:
        log: a log whose images carry ``image`` and ``instance`` (e.g. the synthetic world's).
        min_area: skip masks with fewer pixels.
        object_ids: restrict to these objects (default all).
        frames: restrict to these frame indices (default all).
        margin: pixels of context around each mask's bounding box.

    Returns:
        crops in image order (frame-major, camera order of the log), objects by instance id within an image.
    """
    wanted = set(object_ids) if object_ids is not None else None
    frame_set = set(frames) if frames is not None else None
    by_instance = {o.instance_id: o for o in log.objects if wanted is None or o.object_id in wanted}
    tracks = {t.object_id: t for t in log.tracks}
    out: list[ObjectCrop] = []
    for img in log.images:
        if img.image is None or img.instance is None:
            continue
        if frame_set is not None and img.frame_idx not in frame_set:
            continue
        ids, counts = np.unique(img.instance, return_counts=True)
        for inst, count in zip(ids.tolist(), counts.tolist()):
            obj = by_instance.get(inst)
            if obj is None or count < min_area:
                continue
            row = tracks[obj.object_id].index_of(img.frame_idx)
            if row is None:
                continue
            cut = crop_object(img.image, img.instance == inst, margin)
            if cut is None:
                continue
            rgb, mask, bbox = cut
            out.append(
                ObjectCrop(
                    rgb,
                    mask,
                    obj.category,
                    np.asarray(tracks[obj.object_id].size[row], dtype=np.float64),
                    img.frame_idx,
                    img.camera,
                    obj.object_id,
                    bbox,
                )
            )
    logger.debug("%s: %d object crops (min area %d px)", log.seq_id, len(out), min_area)
    return out
