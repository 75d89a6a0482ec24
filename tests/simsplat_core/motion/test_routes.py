"""Routes of free agents on the two-lane road of ``scenes``: from the log, from the lane graph, straight on for
pedestrians, and the reasons agents are replayed instead."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.predictor import RolloutRequest
from simsplat_core.motion.routes import (
    APPEARS_LATER,
    NO_LANE,
    NOT_OBSERVED,
    REVERSES,
    SHORT_HISTORY,
    STATIC_OBJECT,
    STATIONARY,
    AgentRoute,
    RoutePlan,
    plan_routes,
    project_points,
)
from simsplat_core.motion.traffic_params import PedestrianParams, RouteParams
from simsplat_core.scenario.path import Path
from tests.simsplat_core.motion.scenes import CAR, PERSON, START, TIMES, T, road, states, track

STEPS = np.arange(T)


def _plan(agents: list, valid: dict[str, np.ndarray] | None = None, use_log_routes: bool = True) -> RoutePlan:
    """Plan the routes of every agent but the ego (row 0, fixed)."""
    st = states([("ego", "vehicle", track(-50.0 + 10.0 * TIMES, 3.5), CAR), *agents], valid)
    request = RolloutRequest(st, START, np.array([0]), road(), use_log_routes=use_log_routes)
    return plan_routes(request, RouteParams(), PedestrianParams())


def _route(plan: RoutePlan, row: int) -> AgentRoute:
    (route,) = [r for r in plan.routes if r.row == row]
    return route


def test_project_points_gives_arc_length_and_left_positive_offset() -> None:
    path = Path.from_points(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]))  # east, then north
    s, lateral = project_points(path, np.array([[5.0, 1.0], [11.0, 5.0], [10.0, 12.0]]))
    assert s.tolist() == pytest.approx([5.0, 15.0, 20.0])  # past the end: clamped to it
    assert lateral.tolist() == pytest.approx([1.0, -1.0, 0.0])  # east of a northbound leg is its right


def test_agents_that_cannot_be_driven_are_named_with_the_reason() -> None:
    reversing = {"xy": np.stack([20.0 - 3.0 * TIMES, np.zeros(T)], 1), "heading": np.zeros(T),
                 "speed": np.full(T, -3.0)}  # backs up at 3 m/s facing +x
    plan = _plan([("cone", "static", track(np.full(T, 30.0), -2.5), (0.4, 0.4, 0.7)),
                  ("late", "vehicle", track(10.0 * TIMES, 0.0), CAR),
                  ("gone", "vehicle", track(10.0 * TIMES, 3.5), CAR),
                  ("parked", "vehicle", track(np.full(T, 60.0), 0.0), CAR),
                  ("reversing", "vehicle", reversing, CAR),
                  ("offroad", "vehicle", track(5.0 * TIMES, 50.0), CAR),
                  ("glimpse", "vehicle", track(100.0 + 5.0 * TIMES, 0.0), CAR)],
                 valid={"late": STEPS >= 30, "gone": STEPS < 5, "offroad": STEPS < START,
                        "glimpse": STEPS == START - 1})
    assert plan.routes == ()
    assert plan.replayed == {1: STATIC_OBJECT, 2: APPEARS_LATER, 3: NOT_OBSERVED, 4: STATIONARY, 5: REVERSES,
                             6: NO_LANE, 7: SHORT_HISTORY}


def test_a_logged_route_keeps_the_logged_positions_and_speeds() -> None:
    x = 8.0 * TIMES + 0.25 * TIMES**2  # 8 m/s, speeding up at 0.5 m/s^2
    plan = _plan([("car", "vehicle", track(x, 0.0), CAR), ("left", "vehicle", track(20.0 + 8.0 * TIMES, 3.5), CAR)])
    car = _route(plan, 1)
    assert car.kind == "vehicle" and car.from_log and car.last_valid == T - 1
    assert car.s0 == pytest.approx(x[START - 1] - x[0], abs=0.05)  # arc length from the first logged position
    assert car.offset0 == pytest.approx(0.0, abs=0.01)
    future = np.arange(START, T - 1)
    np.testing.assert_allclose(car.v_ref[future], 8.0 + 0.5 * (TIMES[future] - 0.05), atol=0.05)
    np.testing.assert_allclose(car.path.position(car.s0 + 30.0), [x[START - 1] + 30.0, 0.0], atol=0.05)
    # neighbour lanes: the left one 3.5 m away for the car on lane 0, the right one for the car on lane 1
    assert car.lane_shift[0] == pytest.approx(3.5) and np.isnan(car.lane_shift[1])
    left = _route(plan, 2).lane_shift
    assert np.isnan(left[0]) and left[1] == pytest.approx(-3.5)


def test_desired_speeds_average_out_box_jitter() -> None:
    """A box that jitters 0.2 m along the road from step to step: the logged speed jumps by 4 m/s, the desired
    speed stays near the true 8 m/s and the distance it covers is the log's."""
    jitter = 0.2 * (np.arange(T) % 2)
    plan = _plan([("car", "vehicle", track(8.0 * TIMES + jitter, 0.0), CAR)])
    car = _route(plan, 1)
    raw = np.diff(8.0 * TIMES + jitter) / np.diff(TIMES)
    assert np.ptp(raw[START:]) > 3.0
    future = np.arange(START, T - 6)
    np.testing.assert_allclose(car.v_ref[future], 8.0, atol=0.25)
    travelled = float(np.sum(car.v_ref[START:] * np.diff(TIMES)[START - 1:]))
    assert travelled == pytest.approx(8.0 * (TIMES[-1] - TIMES[START - 1]), rel=0.03)


def test_a_box_wobbling_in_place_is_no_logged_route() -> None:
    """A car whose box wobbles 0.1 m from step to step while it creeps 0.9 m (8 m summed over the future): its log
    fixes no direction, so it takes the lane graph."""
    wobble = track(30.0 + 0.1 * (np.arange(T) % 2) + 0.01 * np.arange(T), 0.0)
    wobble["speed"] = np.full(T, 1.0)  # the velocity field says it moves: not parked
    car = _route(_plan([("car", "vehicle", wobble, CAR)]), 1)
    assert not car.from_log


def test_an_agent_the_log_keeps_in_place_stays_in_place() -> None:
    """A pedestrian whose box jitters in place while its velocity field says 0.6 m/s (no route to follow): its
    desired speeds cover no more than the log's displacement by its last step."""
    jitter = 0.05 * (np.arange(T) % 2)
    person = track(5.0 + jitter, -4.0)
    person["speed"] = np.full(T, 0.6)
    plan = _plan([("p", "pedestrian", person, PERSON)])
    walker = _route(plan, 1)
    assert not walker.from_log
    covered = float(np.sum(walker.v_ref[START:] * np.diff(TIMES)[START - 1:]))
    assert covered <= abs(jitter[-1] - jitter[START - 1]) + 1e-9
    unbound = _plan([("p", "pedestrian", person, PERSON)], use_log_routes=False)
    assert float(unbound.routes[0].v_ref[START:].mean()) == pytest.approx(0.6)  # no log intent: the speed field


def test_a_logged_route_continues_past_the_end_of_the_log() -> None:
    plan = _plan([("car", "vehicle", track(10.0 * TIMES, 0.0), CAR)], valid={"car": STEPS <= 40})
    car = _route(plan, 1)
    assert car.last_valid == 40
    assert car.path.length > 10.0 * TIMES[40] + 200.0  # continued on the lane graph
    np.testing.assert_allclose(car.v_ref[41:], car.v_ref[40], rtol=1e-9)  # the last speed held


def test_without_log_routes_vehicles_follow_the_lane_from_where_they_are() -> None:
    plan = _plan([("car", "vehicle", track(10.0 * TIMES, 0.4), CAR)], use_log_routes=False)
    car = _route(plan, 1)
    assert not car.from_log
    assert car.offset0 == pytest.approx(0.4, abs=1e-6)  # 0.4 m left of the lane centre line
    np.testing.assert_allclose(car.path.position(car.s0 + 50.0), [10.0 * TIMES[START - 1] + 50.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(car.v_ref[START:], 10.0)


def test_pedestrians_walk_straight_on_at_most_at_a_brisk_walk() -> None:
    # heading north at 3 m/s (faster than the 2.5 m/s walking cap)
    runner = track(np.full(T, 30.0), -20.0 + 3.0 * TIMES)
    plan = _plan([("runner", "pedestrian", runner, PERSON)], use_log_routes=False)
    route = _route(plan, 1)
    assert route.kind == "pedestrian" and route.s0 == 0.0 and np.isnan(route.lane_shift).all()
    np.testing.assert_allclose(route.path.position(10.0), [30.0, runner["xy"][START - 1, 1] + 10.0], atol=1e-9)
    assert route.v_ref.max() == pytest.approx(2.5)
    logged = _route(_plan([("runner", "pedestrian", runner, PERSON)]), 1)
    assert logged.from_log and logged.v_ref.max() == pytest.approx(2.5)
