"""Numba compositing kernels: the running-product exponential along a row."""

from __future__ import annotations

import math

import pytest

from simsplat_core.render.cpu_kernels import RUNNING_EXP_MIN, _row_exp


@pytest.mark.parametrize("conic", [(0.05, 0.0, 0.05), (0.3, -0.25, 0.4), (2.0, 0.9, 0.5), (0.01, 0.009, 0.01),
                                   (6.0, 0.0, 6.0)])
def test_running_exponential_matches_direct_exp(conic: tuple[float, float, float]) -> None:
    """``exp(-sigma)`` along a tile row as the kernels form it (one ``_row_exp`` then products) stays
    within 1e-13 relative of ``math.exp(-sigma)`` over 16 pixels, for several row offsets."""
    ca, cb, cc = conic
    assert not _row_exp(True, RUNNING_EXP_MIN - 1, ca, cb, cc, 0.0, 0.0)[0]
    assert not _row_exp(False, 16, ca, cb, cc, 0.0, 0.0)[0]
    step_ratio = math.exp(-ca)
    for dy in (-3.7, -0.5, 0.0, 1.25, 4.0):
        for dx_start in (8.3, 2.5, 0.0, -1.1):
            running, vis_next, ratio = _row_exp(True, 16, ca, cb, cc, dx_start, dy)
            assert running
            for j in range(16):
                dx = dx_start - j
                sigma = 0.5 * (ca * dx * dx + cc * dy * dy) + cb * dx * dy
                want = math.exp(-sigma)
                if want < 1e-250:  # far outside any ellipse the kernels walk
                    break
                assert abs(vis_next - want) <= 1e-13 * want, (conic, dy, dx_start, j)
                vis_next *= ratio
                ratio *= step_ratio

