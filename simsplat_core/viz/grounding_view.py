"""Pictures of a grounding answer: the matched masks over the camera images, and relevance maps.

    panel = grounding_picture(images, masks, relevance)   # uint8 [H', W', 3] for a PNG
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from simsplat_core.scene_view import side_by_side

#: Outline of matched pixels (RGB in [0, 1]): yellow stands out on every car colour of the world.
OUTLINE_COLOR = (1.0, 1.0, 0.0)


def mask_overlay(image: np.ndarray, mask: np.ndarray, color: Sequence[float] = OUTLINE_COLOR, dim: float = 0.35
                 ) -> np.ndarray:
    """``[H, W, 3]`` float image in ``[0, 1]`` with everything outside ``mask [H, W]`` bool darkened to
    ``dim`` and the mask outlined in ``color`` (a tint would vanish on an object of the tint's colour).
    An empty mask leaves the image as it is."""
    if image.shape[:2] != mask.shape:
        raise ValueError(f"mask_overlay: mask {mask.shape} does not match image {image.shape[:2]}")
    out = np.clip(np.asarray(image, np.float32), 0.0, 1.0)  # a new array
    if not mask.any():
        return out
    out[~mask] *= dim
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(out, contours, -1, tuple(float(c) for c in color), 1)
    return out


def relevance_range(relevance: np.ndarray) -> tuple[float, float]:
    """``(low, high)`` colour scale of similarity maps (any shape): their 2nd and 99.5th percentiles."""
    return float(np.percentile(relevance, 2)), float(np.percentile(relevance, 99.5))


def relevance_image(relevance: np.ndarray, low: float | None = None, high: float | None = None) -> np.ndarray:
    """``[H, W]`` similarity -> ``[H, W, 3]`` float heat map in ``[0, 1]`` (blue low, red high), scaled
    between ``low`` and ``high`` (default: the map's own ``relevance_range``)."""
    values = np.asarray(relevance, np.float32)
    own_lo, own_hi = relevance_range(values) if low is None or high is None else (low, high)
    lo = own_lo if low is None else low
    hi = own_hi if high is None else high
    scaled = np.clip((values - lo) / max(hi - lo, 1e-6), 0.0, 1.0)
    heat = cv2.applyColorMap((scaled * 255).astype(np.uint8), cv2.COLORMAP_JET)  # BGR
    return heat[..., ::-1].astype(np.float32) / 255.0


def grounding_picture(images: Sequence[np.ndarray], masks: np.ndarray, relevance: np.ndarray | None = None
                      ) -> np.ndarray:
    """Cameras side by side with the matched masks; below them the relevance maps when given.

    Args:
        images: ``C`` float ``[H, W, 3]`` camera images in ``[0, 1]``.
        masks: ``[C, H, W]`` bool matched pixels.
        relevance: ``[C, H, W]`` similarity maps (one colour scale shared by all cameras), or ``None``.

    Returns:
        uint8 ``[H', W', 3]``.
    """
    if len(images) != masks.shape[0]:
        raise ValueError(f"grounding_picture: {len(images)} images but masks for {masks.shape[0]} cameras")
    top = side_by_side([mask_overlay(img, m) for img, m in zip(images, masks)])
    if relevance is None:
        return top
    lo, hi = relevance_range(relevance)  # one scale for all cameras
    bottom = side_by_side([relevance_image(r, lo, hi) for r in relevance])
    gap = np.zeros((4, top.shape[1], 3), np.uint8)
    return np.concatenate([top, gap, bottom], axis=0)
