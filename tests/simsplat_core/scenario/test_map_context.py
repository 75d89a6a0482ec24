"""Map point queries: polygons, inferred intersections, lane offsets."""

from __future__ import annotations

import numpy as np

from simsplat_core.scenario.geometry import convex_hull, points_in_polygon
from simsplat_core.scenario.map_context import MapContext
from tests.simsplat_core.language.scenes import lane, polygon


def test_points_in_polygon_and_convex_hull() -> None:
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    inside = points_in_polygon(np.array([[1.0, 1.0], [3.0, 1.0], [-0.1, 1.0], [1.0, 1.99]]), square)
    assert inside.tolist() == [True, False, False, True]
    pts = np.concatenate([square, [[1.0, 1.0], [0.5, 1.5]]])
    hull = convex_hull(pts)
    assert len(hull) == 4 and {tuple(p) for p in hull} == {tuple(p) for p in square}


def test_intersection_needs_two_nearby_crosswalks() -> None:
    feats = [
        polygon("drivable_area", "road", -100.0, 100.0, -7.0, 7.0),
        polygon("crosswalk", "a", 10.0, 13.0, -7.0, 7.0),
        polygon("crosswalk", "b", 30.0, 33.0, -7.0, 7.0),
        polygon("crosswalk", "lone", -90.0, -87.0, -7.0, 7.0),
    ]
    ctx = MapContext.from_features(feats)
    assert len(ctx.intersections) == 1
    facts = ctx.facts(np.array([[20.0, 0.0], [-88.0, 0.0], [50.0, 0.0], [20.0, 9.0]]), np.zeros(4))
    assert facts.at_intersection.tolist() == [True, False, False, False]
    assert facts.in_crosswalk.tolist() == [False, True, False, False]
    assert facts.on_drivable.tolist() == [True, True, True, False]


def test_lane_offset_is_signed_left_positive_along_the_heading() -> None:
    ctx = MapContext.from_features([lane("east", 0.0), lane("west", 10.0, reverse=True)])
    xy = np.array([[0.0, 1.0], [0.0, -1.0], [0.0, 1.0], [0.0, 9.0], [0.0, 20.0]])
    heading = np.array([0.0, 0.0, np.pi, np.pi, 0.0])
    facts = ctx.facts(xy, heading)
    np.testing.assert_allclose(facts.lane_offset[:4], [1.0, -1.0, -1.0, 1.0])
    assert np.isnan(facts.lane_offset[4])  # no aligned lane within reach
    np.testing.assert_allclose(facts.lane_dist, [1.0, 1.0, 1.0, 1.0, 10.0])
    # a heading across the lanes has no aligned lane at all
    assert np.isnan(ctx.facts(np.array([[0.0, 1.0]]), np.array([np.pi / 2])).lane_offset[0])
