"""Off-road by road edges (Waymax's definition, for maps without drivable polygons): signed distance to the
nearest road-edge segment on hand-built edges (both side conventions, convex and concave bends, closed
loops), ``offroad_steps`` using edges only without a drivable area, and the convention on the real Waymo
Open Motion sample (logged moving vehicles on the road)."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.scenario import geometry as G
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import offroad_steps
from simsplat_core.types import MapFeature

CAR = (4.0, 2.0, 1.5)


def _edge(points: list[list[float]], fid: str = "e") -> MapFeature:
    pts = np.asarray(points, dtype=np.float64)
    return MapFeature(fid, "road_edge", np.c_[pts, np.zeros(len(pts))])


def _car(xy: list[list[float]], heading: float = 0.0, category: str = "vehicle") -> AgentStates:
    xy_arr = np.asarray(xy, dtype=np.float64)[None]  # [1, T, 2]
    t = xy_arr.shape[1]
    size = (0.6, 0.6, 1.8) if category == "pedestrian" else CAR
    return AgentStates(object_ids=("a",), categories=(category,), sources=("log",), node_ids=np.full(1, -1),
                       frame_idx=np.arange(t), times=np.arange(t) * 0.1, xy=xy_arr, z=np.zeros((1, t)),
                       heading=np.full((1, t), heading), speed=np.zeros((1, t)), size=np.array([size], float),
                       valid=np.ones((1, t), bool))


def test_polyline_segments_link_neighbours_and_close_loops() -> None:
    a, b, nxt, prv = G.polyline_segments([np.array([[0, 0], [1, 0], [1, 0], [2, 0]]),
                                          np.array([[0, 0], [1, 0], [1, 1], [0, 0]])])
    assert len(a) == 5  # the zero-length segment is dropped
    assert nxt.tolist() == [1, -1, 3, 4, 2] and prv.tolist() == [-1, 0, 4, 2, 3]
    empty = G.polyline_segments([])
    assert empty[0].shape == (0, 2) and empty[2].shape == (0,)


@pytest.mark.parametrize("side, sign", [("left", 1.0), ("right", -1.0)])
def test_signed_distance_side_convention(side: str, sign: float) -> None:
    a, b, nxt, prv = G.polyline_segments([np.array([[-10.0, 0.0], [10.0, 0.0]])])  # edge along +x
    d = G.signed_road_edge_distance(np.array([[0.0, 3.0], [0.0, -2.0], [0.0, 0.0]]), a, b, nxt, prv, side)
    np.testing.assert_allclose(d, [3.0 * sign, -2.0 * sign, 0.0])
    with pytest.raises(ValueError, match="road_side"):
        G.signed_road_edge_distance(np.zeros((1, 2)), a, b, road_side="up")
    assert np.isposinf(G.signed_road_edge_distance(np.zeros((2, 2)), np.zeros((0, 2)), np.zeros((0, 2)))).all()


def test_signed_distance_at_bends_uses_the_bisector() -> None:
    # Left turn (east then north): the road (left side) is the convex north-west corner region.
    a, b, nxt, prv = G.polyline_segments([np.array([[-10.0, 0.0], [0.0, 0.0], [0.0, 10.0]])])
    d = G.signed_road_edge_distance(np.array([[1.0, -1.0], [-1.0, 1.0]]), a, b, nxt, prv)
    assert d[0] == pytest.approx(-np.sqrt(2.0))  # beyond the convex corner: off-road (Waymax calls it on-road)
    assert d[1] == pytest.approx(1.0)
    # Right turn (east then south): the road wraps the outside of the bend.
    a, b, nxt, prv = G.polyline_segments([np.array([[-10.0, 0.0], [0.0, 0.0], [0.0, -10.0]])])
    d = G.signed_road_edge_distance(np.array([[1.0, 1.0], [-1.0, -1.0]]), a, b, nxt, prv)
    assert d[0] == pytest.approx(np.sqrt(2.0)) and d[1] == pytest.approx(-1.0)


def test_signed_distance_matches_brute_force_on_a_loop() -> None:
    # A counter-clockwise square: the road (left) is inside, like an island's outline walked the other way.
    square = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [0.0, 20.0], [0.0, 0.0]])
    a, b, nxt, prv = G.polyline_segments([square])
    rng = np.random.default_rng(0)
    pts = rng.uniform(-10.0, 30.0, size=(600, 2))
    d = G.signed_road_edge_distance(pts, a, b, nxt, prv)
    inside = G.points_in_polygon(pts, square[:-1])
    brute = G.segment_distances(pts, a, b).min(axis=1)
    np.testing.assert_allclose(np.abs(d), brute, atol=1e-9)
    assert np.array_equal(d > 0, inside)


def test_offroad_steps_use_road_edges_without_a_drivable_area() -> None:
    # A road between y = -5 and y = 5, its edges walked with the road on their left.
    ctx = MapContext.from_features([_edge([[50, 5], [-50, 5]], "north"), _edge([[-50, -5], [50, -5]], "south")])
    assert ctx.has_road_edges and not ctx.has_drivable and ctx.road_edges.shape == (2, 2, 2)
    car = _car([[0, 0], [0, 3.5], [0, 4.5], [0, 8.0], [0, -4.2]])
    np.testing.assert_array_equal(offroad_steps(car, ctx)[0], [False, False, True, True, True])
    np.testing.assert_array_equal(offroad_steps(car, ctx, tolerance_m=1.0)[0], [False, False, False, True, False])
    # Pedestrians: never off-road by edges (people walk beside the road).
    assert not offroad_steps(_car([[0, 8.0]], category="pedestrian"), ctx).any()
    # The other convention flips the answer.
    flipped = type(ctx)(**{**ctx.__dict__, "road_side": "right"})
    assert offroad_steps(_car([[0, 0]]), flipped)[0, 0]


def test_drivable_area_takes_precedence_over_road_edges() -> None:
    area = MapFeature("d", "drivable_area", np.array([[-50, -5, 0], [50, -5, 0], [50, 5, 0], [-50, 5, 0]], float))
    # A road edge walked the wrong way round would call everything off-road; the polygon decides.
    ctx = MapContext.from_features([area, _edge([[-50, 5], [50, 5]]), _edge([[50, -5], [-50, -5]], "r")])
    assert not offroad_steps(_car([[0, 0]]), ctx).any()
    assert offroad_steps(_car([[0, 8]]), ctx).all()
    assert not offroad_steps(_car([[0, 8]]), MapContext()).any()  # neither polygons nor edges


def test_waymo_sample_vehicles_are_on_the_left_of_road_edges(shared_data) -> None:
    from simsplat_core.data.waymo_scenario import load_waymo_scenario

    log = load_waymo_scenario(shared_data / "waymo" / "motion_data_one_scenario.tfrecord")
    states = AgentStates.from_log(log)
    ctx = MapContext.from_features(log.map_features)
    assert ctx.has_road_edges and not ctx.has_drivable
    rows = [r for r, c in enumerate(states.categories) if c == "vehicle"]
    path = np.array([np.linalg.norm(np.diff(states.xy[r][states.valid[r]], axis=0), axis=1).sum() for r in rows])
    off = offroad_steps(states, ctx, rows)  # [R, T]
    share = off.sum(axis=1) / states.valid[rows].sum(axis=1)
    moving = path > 5.0
    assert moving.sum() >= 20
    assert share[moving].max() == 0.0  # every moving vehicle on the road at every step
    assert share.mean() < 0.1  # a few parked cars stand in lots beyond the kerb
    flipped = type(ctx)(**{**ctx.__dict__, "road_side": "right"})
    flipped_off = offroad_steps(states, flipped, rows)
    assert flipped_off.sum() / states.valid[rows].sum() > 0.8  # the other convention: nearly all off-road
