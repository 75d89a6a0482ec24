"""How complete an asset's Gaussians are, and left-right mirroring of a vehicle seen from one side.

A reconstruction only has Gaussians where the log's cameras looked: a car that drove past the front
cameras is often only its front and one flank. **Side coverage** measures that per side of the box:
for the front (``+x``) the Gaussians in the front half of the box are binned over the side's ``(y, z)``
cells (``COVERAGE_CELLS``), and the coverage is the share of cells holding an opaque one; likewise the
back (``-x``), left (``+y``) and right (``-y``) with ``(x, z)`` cells.

**Mirroring.** Vehicles are left-right symmetric: when one flank is covered much less than the other
(``MIRROR_RATIO``), :func:`mirror_completed` replaces the Gaussians of the poorer half by the mirror
images (``y -> -y``, rotation ``(w, x, y, z) -> (w, -x, y, -z)``) of the better half's.
"""

from __future__ import annotations

import numpy as np
import torch

from simsplat_core.scene.gaussians import GaussianSet

#: Cells across / up a side of the box.
COVERAGE_CELLS = (8, 4)
#: Gaussians at least this opaque count for coverage.
COVERAGE_OPACITY = 0.3
#: Mirror when the poorer flank has less than this share of the better flank's coverage.
MIRROR_RATIO = 0.6
SIDES: tuple[str, ...] = ("front", "back", "left", "right")
_SIDE_AXIS = {"front": (0, 1.0), "back": (0, -1.0), "left": (1, 1.0), "right": (1, -1.0)}


def side_coverage(gaussians: GaussianSet, size: tuple[float, float, float]) -> dict[str, float]:
    """``{"front", "back", "left", "right"} -> share in [0, 1]`` of the side's cells holding an opaque
    Gaussian of that half of the box (``size = (l, w, h)``; Gaussians in the box frame)."""
    means = gaussians.means.detach().cpu().numpy()[gaussians.opacities.detach().cpu().numpy() >= COVERAGE_OPACITY]
    unit = means / (np.asarray(size, dtype=np.float64) / 2.0)  # [-1, 1] inside the box
    out = {}
    for side, (axis, sign) in _SIDE_AXIS.items():
        rows = unit[sign * unit[:, axis] > 0]
        across = np.clip(((rows[:, 1 - axis] + 1.0) / 2.0 * COVERAGE_CELLS[0]).astype(int), 0, COVERAGE_CELLS[0] - 1)
        up = np.clip(((rows[:, 2] + 1.0) / 2.0 * COVERAGE_CELLS[1]).astype(int), 0, COVERAGE_CELLS[1] - 1)
        occupied = np.zeros(COVERAGE_CELLS, dtype=bool)
        occupied[across, up] = True
        out[side] = float(occupied.mean())
    return out


def mirror_completed(gaussians: GaussianSet, size: tuple[float, float, float]) -> tuple[GaussianSet, str]:
    """``(gaussians, which)``: the set with its poorer flank replaced by the mirrored better one when the
    flanks' coverages differ by more than ``MIRROR_RATIO`` (``which`` = ``"left->right"`` /
    ``"right->left"``), else the set unchanged and ``""``. Deformation extras are not mirrored: use it on
    rigid assets."""
    cov = side_coverage(gaussians, size)
    left, right = cov["left"], cov["right"]
    if min(left, right) >= MIRROR_RATIO * max(left, right):
        return gaussians, ""
    sign = 1.0 if left > right else -1.0
    good = gaussians.index(sign * gaussians.means[:, 1] >= 0)
    flip = torch.tensor([1.0, -1.0, 1.0], dtype=good.means.dtype)
    qflip = torch.tensor([1.0, -1.0, 1.0, -1.0], dtype=good.quats.dtype)
    mirrored = good.map_rows(lambda name, t: t * flip if name == "means" else t * qflip if name == "quats" else t)
    mirrored = mirrored.index(sign * mirrored.means[:, 1] < 0)  # Gaussians on the plane are not doubled
    return GaussianSet.cat([good, mirrored]), "left->right" if sign > 0 else "right->left"


__all__ = ["COVERAGE_CELLS", "MIRROR_RATIO", "SIDES", "mirror_completed", "side_coverage"]
