"""Static background scenery: rows of buildings behind the sidewalks and trees in the verges.

Scenery is part of the background (instance id 0) and never moves; its placement is drawn from the
seeded generator so every seed gets a different street front.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.world.mesh import Mesh, building_mesh, tree_mesh
from simsplat_core.world.palette import BUILDING_COLORS, LEAF_COLORS
from simsplat_core.world.road import RoadLayout

REACH = 115.0  # how far along each arm scenery is placed (metres from the junction centre)


def _row(rng: np.random.Generator, start: float, stop: float) -> list[tuple[float, float]]:
    """Consecutive ``(a0, a1)`` intervals (building frontages) between ``start`` and ``stop``."""
    out = []
    a = start + rng.uniform(0.0, 3.0)
    while a < stop:
        w = rng.uniform(8.0, 22.0)
        if rng.random() > 0.15:  # leave the occasional empty lot
            out.append((a, min(a + w, stop)))
        a += w + rng.uniform(0.5, 4.0)
    return out


def build_scenery(layout: RoadLayout, rng: np.random.Generator) -> Mesh:
    """World-space mesh of all buildings and trees around the junction."""
    meshes: list[Mesh] = []
    cx, cy = layout.center
    hv, hh, sw = layout.hw_v, layout.hw_h, layout.sidewalk_w
    for su in (-1.0, 1.0):
        for sv in (-1.0, 1.0):
            setback_h = rng.uniform(1.5, 6.0)
            setback_v = rng.uniform(1.5, 6.0)
            depth_h = rng.uniform(10.0, 16.0)
            depth_v = rng.uniform(10.0, 16.0)
            # along the horizontal road (frontage faces +-v)
            v0 = hh + sw + setback_h
            for a0, a1 in _row(rng, hv + sw + setback_v, REACH):
                height = rng.uniform(6.0, 28.0)
                color = BUILDING_COLORS[int(rng.integers(len(BUILDING_COLORS)))]
                xs = sorted((cx + su * a0, cx + su * a1))
                ys = sorted((cy + sv * v0, cy + sv * (v0 + depth_h)))
                meshes.append(building_mesh(xs[0], xs[1], ys[0], ys[1], height, color))
            # along the vertical road, starting beyond the corner buildings
            u0 = hv + sw + setback_v
            for a0, a1 in _row(rng, v0 + depth_h + 2.0, REACH):
                height = rng.uniform(6.0, 28.0)
                color = BUILDING_COLORS[int(rng.integers(len(BUILDING_COLORS)))]
                xs = sorted((cx + su * u0, cx + su * (u0 + depth_v)))
                ys = sorted((cy + sv * a0, cy + sv * a1))
                meshes.append(building_mesh(xs[0], xs[1], ys[0], ys[1], height, color))
            # trees in the verge between sidewalk and buildings
            if setback_h > 2.5:
                a = hv + sw + setback_v + rng.uniform(2.0, 8.0)
                while a < 70.0:
                    if rng.random() < 0.7:
                        leaf = LEAF_COLORS[int(rng.integers(len(LEAF_COLORS)))]
                        x = cx + su * a
                        y = cy + sv * (hh + sw + setback_h / 2.0)
                        meshes.append(tree_mesh(x, y, rng.uniform(4.5, 8.0), min(setback_h / 2.0, 2.2), leaf))
                    a += rng.uniform(7.0, 13.0)
    return Mesh.concat(meshes)
