"""Procedural static assets: the world's meshes as Gaussians, at the requested size and colour, renderable."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.color_names import DISPLAY_RGB
from simsplat_core.editing.assets.procedural import (
    STATIC_KINDS,
    procedural_asset,
    procedural_assets,
    static_kind_mesh,
    static_subtype_for,
)
from simsplat_core.editing.assets.render import describe_asset, render_asset
from simsplat_core.world.mesh import static_mesh


@pytest.mark.parametrize("subtype", sorted(STATIC_KINDS))
def test_every_kind_fills_its_box(subtype: str) -> None:
    asset = procedural_asset(subtype)
    means = asset.gaussians.means.numpy()
    half = np.asarray(asset.size) / 2
    assert np.all(np.abs(means) <= half + 0.02), subtype  # inside the box (disc centres on the surface)
    extent = means.max(axis=0) - means.min(axis=0)
    assert np.all(extent >= 0.8 * np.asarray(asset.size)), (subtype, extent, asset.size)
    assert means[:, 2].min() == pytest.approx(-half[2], abs=0.02)  # standing on the ground (z = -h / 2)
    assert asset.category == "static" and asset.caption.endswith(subtype) and asset.procedural


@pytest.mark.parametrize(("subtype", "color", "size"), [
    ("traffic cone", "green", (0.5, 0.5, 1.0)),
    ("barrel", "blue", (0.7, 0.7, 1.3)),
    ("jersey barrier", "red", (3.0, 0.6, 0.9)),
    ("excavator", "orange", (5.0, 2.2, 3.0)),
])
def test_requested_size_and_colour(subtype: str, color: str, size: tuple[float, float, float]) -> None:
    asset = procedural_asset(subtype, color, size)
    assert asset.size == pytest.approx(size) and asset.color == color and color in asset.caption
    means = asset.gaussians.means.numpy()
    np.testing.assert_allclose(means.max(axis=0) - means.min(axis=0), size, rtol=0.2)
    # the built-in captioner, looking at renders of the asset, sees the colour asked for
    assert describe_asset(asset).color == color


def test_world_kinds_use_the_world_mesh() -> None:
    size = STATIC_KINDS["barrier"].size
    ours = static_kind_mesh("barrier", size, DISPLAY_RGB["orange"])
    theirs = static_mesh("barrier", size, DISPLAY_RGB["orange"])
    np.testing.assert_array_equal(ours.tris, theirs.tris)
    np.testing.assert_array_equal(ours.color, theirs.color)


def test_renders_show_the_object_in_its_colour() -> None:
    cone = procedural_asset("traffic cone", "orange")
    rgb, alpha = render_asset(cone, size_px=96)
    covered = alpha > 0.5
    assert 0.05 < covered.mean() < 0.6  # an object in the middle of the view, not a blank or a smear
    rows, cols = np.nonzero(covered)
    assert abs((cols.min() + cols.max()) / 2 - 48) < 8 and abs((rows.min() + rows.max()) / 2 - 48) < 8
    assert rows.max() - rows.min() > 60  # the box fills the view
    orange = np.abs(rgb[covered] - np.asarray(DISPLAY_RGB["orange"])).max(axis=1) < 0.25
    assert orange.mean() > 0.4


def test_bank_catalogue_and_errors() -> None:
    assets = procedural_assets()
    assert len(assets) == sum(len(k.colors) for k in STATIC_KINDS.values())
    assert len({a.asset_id for a in assets}) == len(assets)
    assert static_subtype_for("Drum") == "barrel" and static_subtype_for("digger") == "excavator"
    assert static_subtype_for("car") is None
    with pytest.raises(ValueError, match="unknown procedural static object 'bench'"):
        procedural_asset("bench")
    with pytest.raises(ValueError, match="outside"):
        procedural_asset("traffic cone", "orange", (5.0, 5.0, 5.0))
    with pytest.raises(ValueError, match="unknown colour 'teal'"):
        procedural_asset("traffic cone", "teal")
