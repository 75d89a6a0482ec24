"""The bird's-eye view of an edit: where boxes land, their colours, the fitted view, the drawn step."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.types import MapFeature
from simsplat_core.viz.bev import BACKGROUND, EDITED_COLOR, EGO_COLOR, REMOVED_COLOR, bev_extent, default_step, edit_bev
from simsplat_core.viz.contact_sheet import CATEGORY_COLORS, MAP_COLORS
from tests.simsplat_core.viz.scenes import T, assert_tinted, color_mask, straight_agents

SIZE = 400
#: A fixed 40 m view centred on the origin: 10 px per metre, world (x, y) -> pixel (u, v) = (200 - 10 y, 200 - 10 x).
EXTENT = (np.array([-20.0, -20.0]), np.array([20.0, 20.0]))


def _pixel(x: float, y: float) -> tuple[int, int]:
    return round(SIZE / 2 - 10 * y), round(SIZE / 2 - 10 * x)


def _changed_pixels(with_agent: np.ndarray, without: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(u, v)`` of the pixels that differ."""
    v, u = np.nonzero(np.any(with_agent != without, axis=-1))
    return u, v


@pytest.mark.parametrize(("category", "xy"), [("vehicle", (10.0, 5.0)), ("pedestrian", (-8.0, -12.0)),
                                              ("cyclist", (0.0, 15.0))])
def test_an_unchanged_agents_box_lands_at_its_position_in_its_category_colour(category: str,
                                                                             xy: tuple[float, float]) -> None:
    ego = straight_agents(("ego",), ("log",), [(-15.0, 0.0)], step_m=0.0)
    both = straight_agents(("ego", "other"), ("log", "log"), [(-15.0, 0.0), xy], ("vehicle", category), step_m=0.0)
    img = edit_bev([], both, both, step=0, extent=EXTENT, size=SIZE)
    base = edit_bev([], ego, ego, step=0, extent=EXTENT, size=SIZE)
    u, v = _changed_pixels(img, base)
    cu, cv = _pixel(*xy)
    # a 4.5 m x 1.9 m box heading +x (world x is up): 45 px tall, 19 px wide around its centre
    assert abs((u.min() + u.max()) / 2 - cu) <= 1 and abs((v.min() + v.max()) / 2 - cv) <= 1
    # (anti-aliased outlines spread a pixel or so to each side)
    assert u.max() - u.min() == pytest.approx(19, abs=4) and v.max() - v.min() == pytest.approx(45, abs=4)
    # the box's sides (on the row through its centre) in the category colour
    row = img[cv, u.min():u.max() + 1].astype(float)
    assert_tinted(row[np.argmax(np.abs(row - BACKGROUND).sum(axis=1))], CATEGORY_COLORS[category], BACKGROUND)


def test_the_ego_is_filled_where_it_is_at_the_step() -> None:
    st = straight_agents(("ego",), ("log",), [(-10.0, 0.0)])
    img = edit_bev([], st, st, step=7, extent=EXTENT, size=SIZE)
    u, v = _pixel(-10.0 + 7.0, 0.0)
    assert tuple(img[v, u]) == EGO_COLOR


def test_the_edited_box_is_filled_at_the_drawn_step() -> None:
    before = straight_agents(("ego", "car"), ("log", "log"), [(-15.0, -15.0), (-10.0, 6.0)])
    after = straight_agents(("ego", "car"), ("log", "edited"), [(-15.0, -15.0), (-10.0, 6.0)])
    fill = tuple(int(c * 0.5) for c in EDITED_COLOR)
    for step in (0, 9, 15):
        img = edit_bev([], before, after, step=step, extent=EXTENT, size=SIZE)
        u, v = _pixel(-10.0 + step, 6.0)
        assert tuple(img[v, u]) == fill


def test_a_removed_agent_is_crossed_out_where_it_was() -> None:
    before = straight_agents(("ego", "gone"), ("log", "log"), [(-15.0, -15.0), (5.0, 8.0)], step_m=0.0)
    after = before.without(["gone"])
    img = edit_bev([], before, after, step=0, extent=EXTENT, size=SIZE)
    red = color_mask(img, REMOVED_COLOR)
    cu, cv = _pixel(5.0, 8.0)
    v, u = np.nonzero(red[:, :250])  # left of the legend
    assert abs((u.min() + u.max()) / 2 - cu) <= 1 and abs((v.min() + v.max()) / 2 - cv) <= 1
    assert red[cv, cu]  # the cross goes through the centre


def test_map_drawn_under_the_agents() -> None:
    road = MapFeature("road", "drivable_area", np.array([[-5.0, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0.0]]))
    st = straight_agents(("ego",), ("log",), [(-15.0, 0.0)], step_m=0.0)
    img = edit_bev([road], st, st, step=0, extent=EXTENT, size=SIZE)
    assert tuple(img[200, 200]) == MAP_COLORS["drivable_area"]
    assert tuple(img[200, 300]) == (BACKGROUND,) * 3  # outside the road


def test_the_view_fits_the_ego_and_the_changed_agents() -> None:
    before = straight_agents(("ego", "car", "far"), ("log",) * 3, [(0.0, 0.0), (10.0, 3.0), (500.0, 500.0)])
    after = dataclasses.replace(before, sources=("log", "edited", "log"))
    lo, hi = bev_extent(before, after, margin_m=12.0, min_extent_m=40.0)
    # ego x in [0, 19], the edited car in [10, 29] x [3, 3]: x span 29 + 24 m margin, square, centred
    assert (hi - lo).tolist() == pytest.approx([53.0, 53.0])
    assert ((lo + hi) / 2).tolist() == pytest.approx([14.5, 1.5])  # the unchanged far car is not fitted
    small = straight_agents(("ego",), ("log",), [(0.0, 0.0)], step_m=0.0)
    lo, hi = bev_extent(small, small)
    assert (hi - lo).tolist() == pytest.approx([40.0, 40.0])  # the minimum extent


def test_default_step_is_where_the_edit_first_exists() -> None:
    before = straight_agents(("ego", "car"), ("log", "log"), [(0.0, 0.0), (10.0, 3.0)])
    assert default_step(before, before) == 0  # nothing edited
    after = dataclasses.replace(before, sources=("log", "inserted"), valid=before.valid.copy())
    after.valid[1, :6] = False
    assert default_step(before, after) == 6


def test_a_step_outside_the_states_is_an_error() -> None:
    st = straight_agents(("ego",), ("log",), [(0.0, 0.0)])
    with pytest.raises(ValueError, match=rf"step {T} outside \[0, {T}\)"):
        edit_bev([], st, st, step=T)
