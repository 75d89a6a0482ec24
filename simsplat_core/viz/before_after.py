"""Before / after picture of an edit: sampled frames, the original render above the edited one.

    pairs = [FramePair("t=1.0s front", orig_rgb, edit_rgb, orig_mask, edit_mask), ...]
    picture = before_after_picture(pairs, title=prompt)     # uint8 [H', W', 3]

Each column is one sampled frame (frames where the edit shows, each in the camera where it shows most:
:func:`pick_views`); the
pixels of the changed objects are outlined (removed / modified ones in the original row, inserted /
modified ones in the edited row). Pure numpy + OpenCV.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from simsplat_core.viz.images import to_uint8

OUTLINE = (255, 0, 255)  # magenta: stands out on every car and garment colour of the world
LABEL_H = 18
GAP = 4


@dataclass(frozen=True)
class FramePair:
    """One column: ``original`` / ``edited`` ``[H, W, 3]`` float RGB in ``[0, 1]`` (or uint8); ``*_mask [H, W]``
    bool pixels of the changed objects (``None``: nothing outlined)."""

    label: str
    original: np.ndarray
    edited: np.ndarray
    original_mask: np.ndarray | None = None
    edited_mask: np.ndarray | None = None


def sample_steps(active: np.ndarray, count: int = 4) -> list[int]:
    """``count`` steps spread evenly over the steps where ``active [T]`` bool is true (all steps when none
    is), first and last included, without repeats."""
    active = np.asarray(active, bool)
    steps = np.flatnonzero(active) if active.any() else np.arange(active.size)
    if steps.size == 0:
        return []
    picks = np.round(np.linspace(0, steps.size - 1, min(count, steps.size))).astype(int)
    return [int(steps[i]) for i in dict.fromkeys(picks.tolist())]


def pick_views(pixels: np.ndarray, count: int = 4, min_pixels: int = 30) -> list[tuple[int, int]]:
    """``(frame row, camera)`` of up to ``count`` views that show the edit best: among frames where some camera
    sees at least ``min_pixels`` changed pixels (``pixels [F, C]`` counts), the ones with the most changed
    pixels, kept at least ``F / (2 count)`` frames apart so the picture spans the edit, each in its busiest
    camera, in time order. ``[]`` when no frame shows the edit."""
    pixels = np.asarray(pixels)
    best = pixels.max(axis=1)  # [F]
    shown = np.flatnonzero(best >= min_pixels)
    if shown.size == 0:
        return []
    min_gap = max(1, pixels.shape[0] // (2 * count))
    chosen: list[int] = []
    for row in shown[np.argsort(-best[shown], kind="stable")]:
        if all(abs(int(row) - c) >= min_gap for c in chosen):
            chosen.append(int(row))
        if len(chosen) == count:
            break
    return [(row, int(np.argmax(pixels[row]))) for row in sorted(chosen)]


def _panel(image: np.ndarray, mask: np.ndarray | None, scale: float) -> np.ndarray:
    image = np.asarray(image)
    out = (image if image.dtype == np.uint8 else to_uint8(np.clip(image, 0.0, 1.0))).copy()
    if mask is not None and mask.any():
        contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        cv2.drawContours(out, contours, -1, OUTLINE, 1)
    if scale != 1.0:
        size = (round(out.shape[1] * scale), round(out.shape[0] * scale))
        out = cv2.resize(out, size, interpolation=cv2.INTER_LINEAR)
    return out


def _label(width: int, text: str) -> np.ndarray:
    strip = np.zeros((LABEL_H, width, 3), np.uint8)
    cv2.putText(strip, text, (4, LABEL_H - 5), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (230, 230, 230), 1, cv2.LINE_AA)
    return strip


def before_after_picture(pairs: Sequence[FramePair], *, title: str = "", scale: float = 1.5) -> np.ndarray:
    """Columns of ``pairs``: label, original (top) and edited (bottom); a title strip above, row names on
    the left. Returns uint8 ``[H', W', 3]``.

    Raises:
        ValueError: no pairs, or a pair whose images differ in shape.
    """
    if not pairs:
        raise ValueError("before_after_picture: no frames")
    columns = []
    for pair in pairs:
        if pair.original.shape != pair.edited.shape:
            raise ValueError(f"before_after_picture: {pair.label}: original {pair.original.shape} and edited "
                             f"{pair.edited.shape} differ")
        top = _panel(pair.original, pair.original_mask, scale)
        bottom = _panel(pair.edited, pair.edited_mask, scale)
        gap = np.zeros((GAP, top.shape[1], 3), np.uint8)
        columns.append(np.concatenate([_label(top.shape[1], pair.label), top, gap, bottom], axis=0))
    height = max(c.shape[0] for c in columns)
    columns = [np.pad(c, ((0, height - c.shape[0]), (0, 0), (0, 0))) for c in columns]
    spaced: list[np.ndarray] = []
    for c in columns:
        spaced += [c, np.zeros((height, GAP, 3), np.uint8)]
    grid = np.concatenate(spaced[:-1], axis=1)
    names = np.zeros((height, 64, 3), np.uint8)
    panel_h = (height - LABEL_H - GAP) // 2
    for text, y in (("original", LABEL_H + panel_h // 2), ("edited", LABEL_H + GAP + panel_h + panel_h // 2)):
        cv2.putText(names, text, (4, y), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (255, 255, 255), 1, cv2.LINE_AA)
    body = np.concatenate([names, grid], axis=1)
    head = np.zeros((LABEL_H + 4, body.shape[1], 3), np.uint8)
    if title:
        cv2.putText(head, title[:140], (4, LABEL_H - 2), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1,
                    cv2.LINE_AA)
    return np.concatenate([head, body], axis=0)
