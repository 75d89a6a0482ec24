"""Contact sheet of an asset bank: tile layout, row-major tiling, the blank cells, progress."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.viz.asset_sheet import asset_contact_sheet, asset_tile
from tests.simsplat_core.editing.assets.fixtures import walking_pedestrian

TILE = 48
TILE_H = TILE + 3 * 13 + 4  # the render, then three caption lines


@pytest.fixture(scope="module")
def assets() -> list:
    return [walking_pedestrian(asset_id=f"t.ped{k}", step_m=0.1 * (k + 1), frames=8) for k in range(3)]


@pytest.fixture(scope="module")
def tiles(assets: list) -> list[np.ndarray]:
    return [asset_tile(a, TILE) for a in assets]


def test_a_tile_is_the_render_over_its_caption(tiles: list[np.ndarray]) -> None:
    tile = tiles[0]
    assert tile.shape == (TILE_H, TILE, 3) and tile.dtype == np.uint8
    assert (tile[:, -1] == 200).all() and (tile[-1, :] == 200).all()  # grid lines right and below
    render, caption = tile[:TILE, :-1], tile[TILE:-1, :-1]
    assert (render < 250).any(axis=-1).sum() > 0  # the asset is drawn on the white background
    assert (render[0] == 255).all()  # ... which shows around it
    assert (caption.min(axis=-1) < 128).any()  # dark caption text


def test_the_sheet_tiles_row_major_and_pads_the_last_row_with_white(assets: list, tiles: list[np.ndarray]) -> None:
    done: list[tuple[int, int]] = []
    sheet = asset_contact_sheet(assets, columns=2, tile_px=TILE, progress=lambda k, n: done.append((k, n)))
    assert sheet.shape == (2 * TILE_H, 2 * TILE, 3)
    np.testing.assert_array_equal(sheet[:TILE_H, :TILE], tiles[0])
    np.testing.assert_array_equal(sheet[:TILE_H, TILE:], tiles[1])
    np.testing.assert_array_equal(sheet[TILE_H:, :TILE], tiles[2])
    assert (sheet[TILE_H:, TILE:] == 255).all()
    assert done == [(1, 3), (2, 3), (3, 3)]


def test_fewer_assets_than_columns_make_one_row(assets: list) -> None:
    assert asset_contact_sheet(assets[:2], columns=8, tile_px=TILE).shape == (TILE_H, 2 * TILE, 3)
    # at least one column
    assert asset_contact_sheet(assets[:2], columns=0, tile_px=TILE).shape == (2 * TILE_H, TILE, 3)


def test_no_assets_is_an_error() -> None:
    with pytest.raises(ValueError, match="no assets"):
        asset_contact_sheet([])
