"""Tile binning vs a brute-force listing of (tile, Gaussian) pairs."""

from __future__ import annotations

import math

import torch

from simsplat_core.render import isect_tiles, project_gaussians, tile_grid

from .scenes import edge_case_scene, random_scene


def brute_force_lists(means2d, radii, depths, tile_size, tile_width, tile_height):
    """``lists[c][ty][tx]`` = flat ids (c * N + n) of Gaussians touching the tile, nearest first."""
    n_cams, n = radii.shape
    lists = [[[[] for _ in range(tile_width)] for _ in range(tile_height)] for _ in range(n_cams)]
    for c in range(n_cams):
        order = sorted((i for i in range(n) if radii[c, i] > 0), key=lambda i: (float(depths[c, i]), i))
        for i in order:
            r = float(radii[c, i]) / tile_size
            mx, my = float(means2d[c, i, 0]) / tile_size, float(means2d[c, i, 1]) / tile_size
            x0, x1 = max(math.floor(mx - r), 0), min(math.ceil(mx + r), tile_width)
            y0, y1 = max(math.floor(my - r), 0), min(math.ceil(my + r), tile_height)
            for ty in range(y0, y1):
                for tx in range(x0, x1):
                    lists[c][ty][tx].append(c * n + i)
    return lists


def test_isect_tiles_matches_brute_force() -> None:
    for scene, tile_size in ((random_scene(80, n_cams=2, seed=1), 16), (edge_case_scene(n_cams=2), 8)):
        proj = project_gaussians(scene.means, scene.quats, scene.scales, scene.viewmats, scene.Ks, scene.width,
                                 scene.height)
        tw, th = tile_grid(scene.width, scene.height, tile_size)
        isects = isect_tiles(proj.means2d, proj.radii, proj.depths, tile_size, tw, th)
        expected = brute_force_lists(proj.means2d, proj.radii, proj.depths, tile_size, tw, th)
        offsets = isects.isect_offsets.reshape(-1).tolist() + [isects.n_isects]
        ids = isects.flatten_ids.tolist()
        flat_expected = [lst for cam in expected for row in cam for lst in row]
        assert len(flat_expected) == len(offsets) - 1
        for k, want in enumerate(flat_expected):
            assert ids[offsets[k]:offsets[k + 1]] == want, f"tile {k}"
        per_gauss = torch.tensor([[sum(c * proj.radii.shape[1] + i in lst for lst in flat_expected) for i in
                                   range(proj.radii.shape[1])] for c in range(proj.radii.shape[0])], dtype=torch.int32)
        assert torch.equal(isects.tiles_per_gauss, per_gauss)


def test_isect_tiles_empty() -> None:
    means2d = torch.zeros(2, 0, 2)
    isects = isect_tiles(means2d, torch.zeros(2, 0, dtype=torch.int32), torch.zeros(2, 0), 16, 3, 2)
    assert isects.n_isects == 0 and isects.isect_offsets.shape == (2, 2, 3)
    assert bool((isects.isect_offsets == 0).all())
