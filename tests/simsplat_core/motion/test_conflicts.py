"""Gap acceptance: arrival times, and who gives way to an agent crossing the route ahead.

The scene: one driven car (agent 0) on a straight eastbound route along y = 0 at 10 m/s, and a pedestrian
(agent 1) walking north across the route at x = 40 at 1.4 m/s. The corridor is ``|y| < 1.0 + 0.3 + 0.3``
(the car's half width, the pedestrian's half extent across, the margin), so the pedestrian's arrival and
departure follow from where it starts.
"""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.conflicts import DrivenAgents, Predictions, travel_time, yield_gaps
from simsplat_core.motion.corridor import route_pairs
from simsplat_core.motion.lateral import OffsetProfiles
from simsplat_core.motion.route_grid import RouteGrid
from simsplat_core.motion.traffic_params import GapAcceptanceParams
from simsplat_core.scenario.path import Path

GAP = GapAcceptanceParams()  # critical gap 4 s, clearance 1 s, horizon 6 s every 0.3 s, stop margin 1 m
MARGIN = 0.3
X_CROSS = 40.0
WALK = 1.4
CAR = (4.5, 2.0)
PERSON = (0.6, 0.6)


def test_travel_time() -> None:
    accel = np.array([2.0])
    # from standstill: 4 m at 2 m/s^2 take 2 s; 25 m reach 10 m/s after 5 s, 20 m more at 10 m/s take 2 s
    assert travel_time(np.array([4.0]), np.array([0.0]), np.array([10.0]), accel)[0] == pytest.approx(2.0)
    assert travel_time(np.array([45.0]), np.array([0.0]), np.array([10.0]), accel)[0] == pytest.approx(7.0)
    assert travel_time(np.array([30.0]), np.array([10.0]), np.array([10.0]), accel)[0] == pytest.approx(3.0)
    # faster than the desired speed: keeps its speed
    assert travel_time(np.array([30.0]), np.array([15.0]), np.array([10.0]), accel)[0] == pytest.approx(2.0)


def _gap(car_s: float, walker_y0: float, *, walker_driven: bool = False, walker_priority: bool = False,
         critical_s: float = GAP.critical_gap_s) -> tuple[float, int]:
    grid = RouteGrid.from_paths([Path.from_points(np.array([[0.0, 0.0], [300.0, 0.0]]))], 300.0, 1.0)
    width = int(np.ceil(100.0 / grid.step)) + 1
    k0 = grid.window_start(np.array([car_s]), 30.0, width)
    xy = np.array([[car_s, 0.0], [X_CROSS, walker_y0]])
    heading = np.array([0.0, np.pi / 2])
    size = np.array([CAR, PERSON])
    pairs = route_pairs(grid, k0, width, xy[:1], np.array([0]), xy, heading, size, np.zeros((2, 2)),
                        np.ones(2, bool), 100.0)
    assert pairs.j.tolist() == [1]
    tau = np.arange(int(GAP.horizon_s / GAP.sample_dt_s) + 1) * GAP.sample_dt_s
    walker = np.stack([np.full_like(tau, X_CROSS), walker_y0 + WALK * tau], 1)
    car = np.stack([car_s + 10.0 * tau, np.zeros_like(tau)], 1)
    pred = Predictions(xy=np.stack([car, walker]), heading=np.array([np.zeros_like(tau), np.full_like(tau, np.pi / 2)]),
                       valid=np.ones((2, len(tau)), bool), driven=np.array([0, 1 if walker_driven else -1]),
                       priority=np.array([False, walker_priority]), is_vehicle=np.array([True, False]),
                       sample_dt=GAP.sample_dt_s)
    agents = DrivenAgents(s=np.array([car_s]), v=np.array([10.0]), v_plan=np.array([10.0]),
                          half_length=np.array([CAR[0] / 2]), half_width=np.array([CAR[1] / 2]),
                          critical_s=np.array([critical_s]), lookahead_m=np.array([70.0]), max_decel=np.array([8.0]),
                          max_accel=np.array([1.5]), is_pedestrian=np.array([False]), row=np.array([0]))
    profiles = OffsetProfiles(np.zeros(1), np.ones(1), np.zeros(1), np.zeros(1))
    gap, other = yield_gaps(grid, k0, width, pairs, np.array([True]), agents, profiles, pred, size, GAP.stop_margin_m,
                            MARGIN, GAP.clearance_time_s)
    return float(gap[0]), int(other[0])


def test_car_stops_before_a_fixed_pedestrian_stepping_into_its_path() -> None:
    """Starting 6 m south, the walker enters the corridor after 3.3 s (under the 4 s critical gap) and stays until
    5.7 s; the car (front at 12.25 m) would reach the zone at 39.7 m after 2.7 s: they overlap. A fixed walker will
    not react, so the car stops the stop margin before the zone."""
    gap, other = _gap(10.0, -6.0)
    assert other == 1
    assert gap == pytest.approx((X_CROSS - PERSON[1] / 2) - GAP.stop_margin_m - (10.0 + CAR[0] / 2))


def test_no_yield_when_the_arrival_is_beyond_the_critical_gap() -> None:
    assert _gap(10.0, -6.0, critical_s=3.0) == (np.inf, -1)  # arrives at 3.3 s


def test_no_yield_when_the_walker_has_crossed_before_the_car_arrives() -> None:
    # from 2 m south: in the corridor from 0.3 s to 2.7 s; the car reaches the zone only after 2.7 s (27.45 m)
    assert _gap(10.0, -2.0) == (np.inf, -1)


def test_between_driven_agents_the_first_to_arrive_goes_unless_the_other_has_priority() -> None:
    # the car arrives (2.7 s) before the walker (3.3 s) and can stop: it goes first
    assert _gap(10.0, -6.0, walker_driven=True) == (np.inf, -1)
    # a pedestrian on a crosswalk goes first
    gap, other = _gap(10.0, -6.0, walker_driven=True, walker_priority=True)
    assert other == 1 and np.isfinite(gap)


def test_a_committed_car_drives_on_but_brakes_for_a_fixed_agent_anyway() -> None:
    """3.45 m before the zone at 10 m/s (stopping takes 6.25 m at the hard-brake limit): the car cannot stop.
    A walker that gives way would let it through; a fixed one will not, so the car brakes as hard as it can."""
    gap, other = _gap(33.0, -2.0, walker_driven=True, walker_priority=True)
    assert (gap, other) == (np.inf, -1)
    gap, other = _gap(33.0, -2.0)
    assert other == 1 and gap == pytest.approx((X_CROSS - 0.3) - GAP.stop_margin_m - (33.0 + CAR[0] / 2))


def test_nothing_to_yield_to_behind_the_car() -> None:
    assert _gap(45.0, -6.0) == (np.inf, -1)  # the crossing lies behind the car's front
