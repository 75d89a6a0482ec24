"""Overlap tests between agents' ground footprints (oriented rectangles), vectorised over frames.

Used by the population step to reject candidate agents whose trajectory would interpenetrate an
already placed one at any frame.
"""

from __future__ import annotations

import numpy as np


def footprints_overlap(
    center_a: np.ndarray,
    heading_a: np.ndarray,
    size_a: tuple[float, float],
    center_b: np.ndarray,
    heading_b: np.ndarray,
    size_b: tuple[float, float],
    margin: float = 0.0,
) -> np.ndarray:
    """Per-frame overlap of two oriented rectangles (separating-axis test).

    Args:
        center_a, center_b: ``[T, 2]`` footprint centres.
        heading_a, heading_b: ``[T]`` yaw of the length axis.
        size_a, size_b: ``(length, width)``.
        margin: clearance added to both half extents of ``a``.

    Returns:
        ``[T]`` bool, true where the rectangles (``a`` grown by ``margin``) intersect.
    """
    ha = np.array([size_a[0] / 2.0 + margin, size_a[1] / 2.0 + margin])
    hb = np.array([size_b[0] / 2.0, size_b[1] / 2.0])
    ua = np.stack([np.cos(heading_a), np.sin(heading_a)], axis=-1)
    va = np.stack([-np.sin(heading_a), np.cos(heading_a)], axis=-1)
    ub = np.stack([np.cos(heading_b), np.sin(heading_b)], axis=-1)
    vb = np.stack([-np.sin(heading_b), np.cos(heading_b)], axis=-1)
    delta = center_b - center_a
    separated = np.zeros(delta.shape[0], dtype=bool)
    for axis in (ua, va, ub, vb):
        ra = ha[0] * np.abs(np.sum(ua * axis, -1)) + ha[1] * np.abs(np.sum(va * axis, -1))
        rb = hb[0] * np.abs(np.sum(ub * axis, -1)) + hb[1] * np.abs(np.sum(vb * axis, -1))
        separated |= np.abs(np.sum(delta * axis, -1)) > ra + rb
    return ~separated
