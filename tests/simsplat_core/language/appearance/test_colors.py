"""Colour naming: palette patches under shading, vehicle bodies with windows and tyres, clothing bands."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.color_names import CHROMATIC_PALETTE
from simsplat_core.language.appearance.colors import (
    CLOTHING_SCALE,
    UNKNOWN,
    chromaticity,
    clothing_colors,
    dominant_color,
    erode_mask,
    kmeans,
    name_lab,
    region_colors,
    rgb_to_lab,
    vehicle_body_color,
)
from tests.simsplat_core.language.appearance.helpers import GLASS, PAINTS, SHADE, paint_pedestrian, paint_vehicle, patch

CHROMATIC = [n for n in PAINTS if n not in ("black", "white", "silver", "gray")]


@pytest.mark.parametrize("name", CHROMATIC)
@pytest.mark.parametrize("factor", [SHADE, 0.85, 1.0, 1.2])
def test_chromatic_patch_named_under_any_shading(name, factor):
    rgb, _ = patch(PAINTS[name], factor)
    assert name_lab(rgb_to_lab(rgb[0, 0])).name == name


@pytest.mark.parametrize("name", [c.name for c in CHROMATIC_PALETTE])
def test_palette_references_name_themselves(name):
    ref = next(c for c in CHROMATIC_PALETTE if c.name == name)
    decision = name_lab(rgb_to_lab(np.array(ref.rgb)))
    assert decision.name == name
    assert decision.confidence > 0.9


@pytest.mark.parametrize("name", ["black", "gray", "silver", "white"])
def test_achromatic_surface_in_ambient_light(name):
    # the least-lit face of an object sits in ambient light (factor ~0.64); that is what names it
    rgb, mask = patch(PAINTS[name], SHADE)
    regions = region_colors(rgb_to_lab(rgb[mask]))
    assert regions[0].name == name


def test_chromaticity_is_nearly_shading_invariant():
    dim = chromaticity(rgb_to_lab(np.array(PAINTS["red"]) * SHADE))
    bright = chromaticity(rgb_to_lab(np.array(PAINTS["red"]) * 1.2))
    assert np.linalg.norm(dim - bright) < 0.1 * np.linalg.norm(bright)


@pytest.mark.parametrize("name", ["red", "blue", "green", "yellow", "white", "silver", "gray"])
def test_vehicle_body_ignores_windows_and_tyres(name):
    rgb, mask = paint_vehicle(PAINTS[name])
    assert vehicle_body_color(rgb, mask).name == name


def test_black_car_with_dark_windows_is_black():
    rgb, mask = paint_vehicle(PAINTS["black"])
    estimate = vehicle_body_color(rgb, mask)
    assert estimate.name == "black"
    assert any(r.glass_like for r in estimate.regions)  # the windows were seen, and set aside


def test_white_car_lit_and_shaded_faces_stay_white():
    rgb, mask = paint_vehicle(PAINTS["white"], faces=(SHADE, 1.2))
    assert vehicle_body_color(rgb, mask).name == "white"


def test_gray_car_is_not_silver_even_when_sunlit():
    rgb, mask = paint_vehicle(PAINTS["gray"], faces=(SHADE, 1.2))
    assert vehicle_body_color(rgb, mask).name == "gray"


def test_vehicle_seen_only_through_its_windows_is_unknown():
    rgb, mask = patch(GLASS, 0.9)
    assert vehicle_body_color(rgb, mask).name == UNKNOWN


def test_mask_selects_the_object_not_the_background():
    rgb, mask = paint_vehicle(PAINTS["red"])
    rgb[~mask] = PAINTS["blue"]
    assert vehicle_body_color(rgb, mask).name == "red"


def test_dominant_color_prefers_chromatic_over_white_band():
    rgb, mask = patch(PAINTS["orange"], 1.0, size=30)
    rgb[12:18] = PAINTS["white"]  # a cone's reflective band
    estimate = dominant_color(rgb, mask)
    assert estimate.name == "orange"
    assert "white" in estimate.names


@pytest.mark.parametrize(
    ("upper", "lower"),
    [("red", "blue"), ("white", "black"), ("yellow", "beige"), ("green", "brown"), ("black", "gray"), ("gray", "blue")],
)
def test_pedestrian_upper_and_lower_colors(upper, lower):
    rgb, mask = paint_pedestrian(PAINTS[upper], PAINTS[lower])
    top, bottom = clothing_colors(rgb, mask)
    assert (top.name, bottom.name) == (upper, lower)


def test_clothing_scale_has_no_silver():
    names = {CLOTHING_SCALE.name(v) for v in np.linspace(0, 100, 201)}
    assert names == {"black", "gray", "white"}


def test_erode_mask_shrinks_large_masks_and_keeps_thin_ones():
    big = np.zeros((20, 20), bool)
    big[2:18, 2:18] = True
    assert erode_mask(big).sum() < big.sum()
    assert not (erode_mask(big) & ~big).any()
    thin = np.zeros((20, 20), bool)
    thin[5, 2:18] = True
    assert np.array_equal(erode_mask(thin), thin)


def test_kmeans_is_deterministic_and_separates_clusters():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(c, 1.0, size=(50, 3)) for c in (0.0, 30.0, 60.0)])
    labels_a, centres_a = kmeans(x, 3)
    labels_b, centres_b = kmeans(x[::-1].copy(), 3)
    assert np.allclose(np.sort(centres_a[:, 0]), np.sort(centres_b[:, 0]))
    assert len(set(labels_a[:50])) == len(set(labels_a[50:100])) == len(set(labels_a[100:])) == 1
    assert len(set(labels_a.tolist())) == 3


def test_empty_mask_gives_unknown():
    rgb = np.zeros((8, 8, 3), np.float32)
    empty = np.zeros((8, 8), bool)
    assert vehicle_body_color(rgb, empty).name == UNKNOWN
    assert dominant_color(rgb, empty).name == UNKNOWN
    assert clothing_colors(rgb, empty)[0].name == UNKNOWN
