"""Rollout metrics on hand-built straight-line scenarios: exact ADE / FDE, invalid log steps skipped, horizons
beyond the data undefined, collisions of log agents counted unless the baseline has them, off-road,
progress and stopped agents, rates."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from simsplat_core.scenario import rollout_metrics as R
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext

DT = 0.1
T = 50
START = 10
CAR = (4.5, 2.0, 1.5)
PERSON = (0.6, 0.6, 1.8)


def _states(xy: np.ndarray, categories: list[str], ids: list[str] | None = None,
            valid: np.ndarray | None = None) -> AgentStates:
    """``xy [A, T, 2]`` agents heading along +x, sources ``log``."""
    a, t = xy.shape[:2]
    size = np.array([PERSON if c == "pedestrian" else CAR for c in categories], dtype=np.float64)
    return AgentStates(object_ids=tuple(ids or [f"a{i}" for i in range(a)]), categories=tuple(categories),
                       sources=("log",) * a, node_ids=np.full(a, -1), frame_idx=np.arange(t),
                       times=np.arange(t) * DT, xy=xy, z=np.zeros((a, t)), heading=np.zeros((a, t)),
                       speed=np.zeros((a, t)), size=size, valid=np.ones((a, t), bool) if valid is None else valid)


def _lines(speeds: list[float], lanes_y: list[float]) -> np.ndarray:
    """``[A, T, 2]`` constant-speed straight lines along +x, agent ``i`` on ``y = lanes_y[i]``."""
    t = np.arange(T) * DT
    return np.stack([np.c_[v * t, np.full(T, y)] for v, y in zip(speeds, lanes_y)])


def _shift_future(xy: np.ndarray, rows: list[int], dy: float) -> np.ndarray:
    out = xy.copy()
    out[rows, START + 1:, 1] += dy
    return out


# ------------------------------------------------------------------------------------------ ADE / FDE
def test_identical_rollout_has_zero_error_and_full_progress() -> None:
    log = _states(_lines([10.0, 1.4], [0.0, 20.0]), ["vehicle", "pedestrian"], ids=["ego", "p1"])
    err = R.displacement_errors(log, log, START)
    assert err.object_ids == ("ego", "p1") and err.horizon_steps == (30, 80)
    np.testing.assert_array_equal(err.ade[:, 0], [0.0, 0.0])
    np.testing.assert_array_equal(err.fde[:, 0], [0.0, 0.0])
    prog = R.progress_and_stops(log, log, START)
    assert prog.progress == pytest.approx(1.0) and prog.stopped_share == 0.0
    assert prog.object_ids == ("ego", "p1")


def test_offset_by_one_metre_gives_ade_and_fde_one_and_no_8s_beyond_data() -> None:
    xy = _lines([10.0, 10.0], [0.0, 10.0])
    log = _states(xy, ["vehicle", "vehicle"])
    roll = _states(_shift_future(xy, [0, 1], 1.0), ["vehicle", "vehicle"])
    err = R.displacement_errors(roll, log, START)
    np.testing.assert_allclose(err.ade[:, 0], 1.0)
    np.testing.assert_allclose(err.fde[:, 0], 1.0)
    assert np.isnan(err.ade[:, 1]).all() and np.isnan(err.fde[:, 1]).all()  # 80 steps after step 10 > 50 steps
    assert err.mean(3.0) == pytest.approx((1.0, 1.0))
    assert err.as_row() == {"ade_3s": pytest.approx(1.0), "fde_3s": pytest.approx(1.0), "ade_8s": None,
                            "fde_8s": None}


def test_error_only_inside_the_horizon_and_only_after_start() -> None:
    xy = _lines([10.0], [0.0])
    log = _states(xy, ["vehicle"])
    moved = xy.copy()
    moved[0, :START + 1, 1] += 50.0  # the history (start step included) does not count
    moved[0, START + 31:, 1] += 50.0  # nor anything after the 3 s horizon
    moved[0, START + 1:START + 31, 1] += 2.0
    err = R.displacement_errors(_states(moved, ["vehicle"]), log, START, horizons_s=(3.0,))
    assert err.ade[0, 0] == pytest.approx(2.0) and err.fde[0, 0] == pytest.approx(2.0)


def test_invalid_log_steps_are_skipped_and_fde_undefined_there() -> None:
    xy = _lines([10.0], [0.0])
    valid = np.ones((1, T), bool)
    valid[0, START + 5:START + 10] = False  # the log lost the track for 5 steps
    valid[0, START + 30] = False  # and at the 3 s horizon step
    log = _states(xy, ["vehicle"], valid=valid)
    rolled = _shift_future(xy, [0], 1.0)
    rolled[0, START + 5:START + 10, 1] += 100.0  # wherever the rollout is there, it does not count
    rolled[0, START + 30, 1] += 100.0
    err = R.displacement_errors(_states(rolled, ["vehicle"]), log, START, horizons_s=(3.0, 2.0))
    assert err.ade[0, 0] == pytest.approx(1.0) and np.isnan(err.fde[0, 0])
    assert err.ade[0, 1] == pytest.approx(1.0) and err.fde[0, 1] == pytest.approx(1.0)


def test_errors_per_agent_type_and_matching_by_id() -> None:
    xy = _lines([10.0, 1.4, 5.0], [0.0, 20.0, 40.0])
    log = _states(xy, ["vehicle", "pedestrian", "cyclist"], ids=["car", "ped", "bike"])
    rolled = xy.copy()
    for row, dy in ((0, 1.0), (1, 2.0), (2, 3.0)):
        rolled[row, START + 1:, 1] += dy
    # the rollout lists the agents in another order, drops the cyclist and adds an agent the log lacks
    roll = _states(np.stack([rolled[1], rolled[0], rolled[0] + 100.0]), ["pedestrian", "vehicle", "vehicle"],
                   ids=["ped", "car", "new"])
    err = R.displacement_errors(roll, log, START)
    assert err.object_ids == ("car", "ped") and err.types == ("vehicle", "pedestrian")
    by_type = err.by_type()
    assert by_type["vehicle"]["ade_3s"] == pytest.approx(1.0)
    assert by_type["pedestrian"]["fde_3s"] == pytest.approx(2.0)
    assert math.isnan(by_type["pedestrian"]["ade_8s"])
    assert R.agent_type("cyclist") == "cyclist" and R.agent_type("other") == "vehicle"


def test_rollout_and_log_must_share_steps() -> None:
    log = _states(_lines([10.0], [0.0]), ["vehicle"])
    short = _states(_lines([10.0], [0.0])[:, :-1], ["vehicle"])
    with pytest.raises(ValueError, match="share their steps"):
        R.displacement_errors(short, log, START)
    with pytest.raises(IndexError):
        R.progress_and_stops(log, log, T)


# ------------------------------------------------------------------------------------------ failures
def _parked(first: tuple[float, float], second: tuple[float, float]) -> AgentStates:
    xy = np.zeros((3, T, 2))
    xy[0] = [-50.0, 0.0]  # the ego, far away
    xy[1], xy[2] = first, second
    return _states(xy, ["vehicle", "vehicle", "vehicle"], ids=["ego", "c1", "c2"])


def test_collision_between_two_log_agents_is_a_failure() -> None:
    log = _parked((0.0, 0.0), (0.0, 10.0))
    roll_xy = log.xy.copy()
    roll_xy[2, START + 1:] = [1.0, 0.5]  # c2 ends up inside c1 (an instantaneous jump, also kinematic)
    roll = replace(log, xy=roll_xy)
    fail = R.scenario_failures(roll, MapContext(), baseline=log)
    assert fail.collision_vehicle and not fail.collision_pedestrian and fail.failure
    assert set(fail.failed_agents) >= {"c1", "c2"} and "ego" not in fail.failed_agents
    assert not R.scenario_failures(log, MapContext()).failure


def test_overlap_already_in_the_baseline_is_not_counted() -> None:
    log = _parked((0.0, 0.0), (1.0, 0.5))  # two parked cars whose logged boxes overlap
    assert R.scenario_failures(log, MapContext()).collision_vehicle  # the log's own rate counts it
    fail = R.scenario_failures(log, MapContext(), baseline=log)
    assert not fail.failure and fail.failed_agents == ()


def test_pedestrian_collision_and_offroad_of_rows() -> None:
    xy = np.zeros((2, T, 2))
    xy[1] = [0.5, 0.0]
    states = _states(xy, ["vehicle", "pedestrian"])
    fail = R.scenario_failures(states, MapContext(), rows=[0])
    assert fail.collision_pedestrian and not fail.collision_vehicle and fail.failed_agents == ("a0",)
    road = MapContext(drivable=(np.array([[-10.0, -3.0], [10.0, -3.0], [10.0, 3.0], [-10.0, 3.0]]),))
    car = _states(_lines([0.0], [2.5]), ["vehicle"])  # half of the box beyond the road edge at y = 3
    off = R.scenario_failures(car, road)
    assert off.offroad and off.failure and not off.collision_vehicle
    # against a baseline, an agent still on its baseline trajectory brings its off-road with it; a moved one does not
    assert not R.scenario_failures(car, road, baseline=car).offroad
    moved = _states(_lines([0.0], [2.6]), ["vehicle"])
    assert R.scenario_failures(moved, road, baseline=car).offroad
    assert R.unchanged_rows(moved, [0], car).tolist() == [False]
    assert R.unchanged_rows(car, [0], None).tolist() == [False]


def test_rates_are_shares_of_scenarios() -> None:
    ok, crash = R.ScenarioFailures(), R.ScenarioFailures(collision_vehicle=True, offroad=True)
    got = R.rates([ok, crash, ok, ok])
    assert got == {"collision_vehicle": 0.25, "collision_pedestrian": 0.0, "offroad": 0.25, "kinematic": 0.0,
                   "failure": 0.25}
    assert R.ScenarioFailures(collision_static=True).failure
    with pytest.raises(ValueError):
        R.rates([])


# ------------------------------------------------------------------------------------------ progress
def test_stopped_agent_counts_in_stopped_share_and_lowers_progress() -> None:
    xy = _lines([10.0, 10.0, 0.0], [0.0, 10.0, 20.0])  # the third agent is parked in the log too
    log = _states(xy, ["vehicle", "vehicle", "vehicle"])
    rolled = xy.copy()
    stop = START + 20  # a1 stops 2 s into the rollout and never moves again
    rolled[1, stop:] = rolled[1, stop]
    prog = R.progress_and_stops(_states(rolled, ["vehicle"] * 3), log, START)
    assert prog.object_ids == ("a0", "a1")  # the parked one never moved: neither progress nor stops
    np.testing.assert_array_equal(prog.stopped, [False, True])
    assert prog.stopped_share == pytest.approx(0.5)
    logged = 10.0 * DT * (T - 1 - START)
    np.testing.assert_allclose(prog.ratios, [1.0, 10.0 * DT * (stop - START) / logged])
    assert prog.progress == pytest.approx((1.0 + prog.ratios[1]) / 2.0)
    assert prog.as_row() == {"progress": pytest.approx(prog.progress), "stopped_share": pytest.approx(0.5)}


def test_a_stopped_box_that_jitters_is_stopped() -> None:
    """A car that stops for good in the log, its box jittering 6 cm a step afterwards (0.6 m/s from one step to
    the next): stopped in the log as in a rollout that stops it smoothly. A pedestrian walking at 0.7 m/s with
    the same jitter is not."""
    xy = _lines([10.0, 10.0, 0.7], [0.0, 10.0, 20.0])
    stop = START + 20
    xy[1, stop:] = xy[1, stop]
    smooth = xy.copy()
    jitter = 0.06 * (np.arange(T) % 2)
    xy[1, stop:, 0] += jitter[stop:]
    xy[2, :, 0] += jitter
    kinds = ["vehicle", "vehicle", "pedestrian"]
    log = _states(xy, kinds)
    for states in (log, _states(smooth, kinds)):
        np.testing.assert_array_equal(R.progress_and_stops(states, log, START).stopped, [False, True, False])


def test_progress_is_clipped_and_undefined_without_moving_agents() -> None:
    log = _states(_lines([5.0], [0.0]), ["vehicle"])
    fast = _states(_lines([50.0], [0.0]), ["vehicle"])
    assert R.progress_and_stops(fast, log, START).progress == R.PROGRESS_CLIP[1]
    parked = _states(_lines([0.0], [0.0]), ["vehicle"])
    prog = R.progress_and_stops(parked, parked, START)
    assert math.isnan(prog.progress) and math.isnan(prog.stopped_share)
    assert prog.as_row() == {"progress": None, "stopped_share": None}
