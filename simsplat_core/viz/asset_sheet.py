"""Contact sheet of an asset bank: each asset rendered alone from the same 3/4 view, tiled with captions.

    sheet = asset_contact_sheet(bank.assets)     # uint8 [H, W, 3] for a PNG
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence

import cv2
import numpy as np

from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.assets.render import render_asset
from simsplat_core.viz.images import to_uint8

logger = logging.getLogger(__name__)

#: Caption lines under each tile: id, caption, "l x w x h m, N Gaussians[, walks x m]".
_FONT = cv2.FONT_HERSHEY_SIMPLEX
_TEXT_SCALE = 0.36
_LINE_PX = 13


def _fit(text: str, width: int) -> str:
    """``text`` shortened with "..." to fit ``width`` pixels."""
    while text and cv2.getTextSize(text, _FONT, _TEXT_SCALE, 1)[0][0] > width - 6:
        text = text[:-4] + "..." if len(text) > 4 else ""
    return text


def _lines(asset: Asset) -> list[str]:
    length, width, height = asset.size
    facts = f"{length:.1f}x{width:.1f}x{height:.1f} m, {asset.num_gaussians} G"
    if asset.deformable:
        facts += f", walks {asset.walked_m:.1f} m"
    return [asset.asset_id, asset.caption, facts]


def asset_tile(asset: Asset, tile_px: int = 180) -> np.ndarray:
    """``[tile_px + 3 lines, tile_px, 3]`` uint8: the render on white with the caption lines below."""
    rgb, _ = render_asset(asset, size_px=tile_px)
    lines = _lines(asset)
    text = np.full((_LINE_PX * len(lines) + 4, tile_px, 3), 255, np.uint8)
    for k, line in enumerate(lines):
        color = (0, 0, 0) if k == 1 else (90, 90, 90)
        cv2.putText(text, _fit(line, tile_px), (3, _LINE_PX * (k + 1)), _FONT, _TEXT_SCALE, color, 1, cv2.LINE_AA)
    tile = np.concatenate([to_uint8(rgb), text], axis=0)
    tile[:, -1] = 200  # a thin grid line
    tile[-1, :] = 200
    return tile


def asset_contact_sheet(assets: Sequence[Asset], columns: int = 8, tile_px: int = 180,
                        progress: Callable[[int, int], None] | None = None) -> np.ndarray:
    """``[H, W, 3]`` uint8 grid of :func:`asset_tile` (row-major in the given order).

    Args:
        progress: called as ``progress(done, total)`` after each tile.

    Raises:
        ValueError: no assets.
    """
    if not assets:
        raise ValueError("asset_contact_sheet: no assets to draw")
    tiles = []
    for k, asset in enumerate(assets):
        tiles.append(asset_tile(asset, tile_px))
        if progress is not None:
            progress(k + 1, len(assets))
    columns = max(1, min(columns, len(tiles)))
    blank = np.full_like(tiles[0], 255)
    rows = [np.concatenate((tiles[i:i + columns] + [blank] * columns)[:columns], axis=1)
            for i in range(0, len(tiles), columns)]
    logger.info("contact sheet of %d assets (%d x %d tiles)", len(tiles), len(rows), columns)
    return np.concatenate(rows, axis=0)


__all__ = ["asset_contact_sheet", "asset_tile"]
