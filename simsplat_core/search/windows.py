"""Per-frame truth -> frame windows ``[start, end]`` (inclusive)."""

from __future__ import annotations

import numpy as np


def frame_windows(truth: np.ndarray, min_frames: int = 3, max_gap: int = 2) -> list[tuple[int, int]]:
    """Windows of consecutive true frames.

    Args:
        truth: ``[F]`` bool, one entry per log frame.
        min_frames: windows shorter than this are dropped (a one-frame blip of a label is noise).
        max_gap: false runs of at most this many frames between two true runs are bridged first.

    Returns:
        ``[(first frame, last frame), ...]`` in frame order.
    """
    truth = np.asarray(truth, dtype=bool)
    runs: list[list[int]] = []
    for i in np.flatnonzero(truth):
        if runs and i - runs[-1][1] <= max_gap + 1:
            runs[-1][1] = int(i)
        else:
            runs.append([int(i), int(i)])
    return [(a, b) for a, b in runs if b - a + 1 >= min_frames]


def covered(windows: list[tuple[int, int]], num_frames: int) -> np.ndarray:
    """``[num_frames]`` bool: frames inside any of ``windows``."""
    out = np.zeros(num_frames, dtype=bool)
    for a, b in windows:
        out[max(a, 0): b + 1] = True
    return out
