"""Real-data rollout evaluation: baselines and the MotionMap builder on hand-built scenarios (a map without
lanes included), resampling to 10 Hz, the motion table's rows, and both real samples (skipped when
../shared/data is absent)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from simsplat_core.data.errors import CorruptLogError
from simsplat_core.eval.refinement import real as R
from simsplat_core.eval.refinement.table import MOTION_COLUMNS, MOTION_SPEC, motion_rows, motion_table
from simsplat_core.motion.baselines import NOT_OBSERVED, ConstantVelocityPredictor, LogReplayPredictor
from simsplat_core.motion.motion_map import motion_map_from_features
from simsplat_core.motion.predictor import MotionPredictor, RolloutRequest
from simsplat_core.motion.registry import available_predictors, make_predictor
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.types import MapFeature

T = 100
DT = 0.1


def _states(hz: float = 10.0, steps: int = T) -> AgentStates:
    """The ego and two cars driving along +x at 10 and 5 m/s on separate lanes, a pedestrian appearing late."""
    t = np.arange(steps) / hz
    xy = np.stack([np.c_[10.0 * t, np.zeros(steps)], np.c_[20.0 + 5.0 * t, np.full(steps, 4.0)],
                   np.c_[-30.0 + 8.0 * t, np.full(steps, -4.0)], np.c_[np.full(steps, 5.0), 12.0 + 0.0 * t]])
    valid = np.ones((4, steps), bool)
    valid[3, : steps // 2] = False
    return AgentStates(object_ids=(EGO_ID, "a", "b", "p"), categories=("vehicle", "vehicle", "vehicle", "pedestrian"),
                       sources=("log",) * 4, node_ids=np.full(4, -1), frame_idx=np.arange(steps), times=t, xy=xy,
                       z=np.zeros((4, steps)), heading=np.zeros((4, steps)),
                       speed=np.array([[10.0], [5.0], [8.0], [0.0]]).repeat(steps, axis=1),
                       size=np.array([[4.8, 2.0, 1.6], [4.5, 2.0, 1.5], [4.5, 2.0, 1.5], [0.6, 0.6, 1.8]]),
                       valid=valid)


def _scenario(features: list[MapFeature] | None = None) -> R.RealScenario:
    return R.RealScenario(dataset="hand", seq_id="s0", states=_states(), map=motion_map_from_features(features or []))


def test_baselines_follow_the_protocol() -> None:
    scenario = _scenario()
    request = scenario.request()
    for predictor in (LogReplayPredictor(), ConstantVelocityPredictor()):
        assert isinstance(predictor, MotionPredictor)
    assert LogReplayPredictor().rollout(request).states is request.states
    roll = ConstantVelocityPredictor().rollout(request)
    assert roll.predictor == "constant-velocity"
    s, log = roll.states, request.states
    np.testing.assert_allclose(s.xy[:3], log.xy[:3], atol=1e-9)  # constant-speed lines are exact
    assert s.sources == ("log", "refined", "refined", "log")  # the ego is fixed
    assert roll.replayed == {"p": NOT_OBSERVED}  # absent at the last history step
    np.testing.assert_array_equal(s.valid[3], log.valid[3])


def test_constant_velocity_extrapolates_from_the_last_history_step() -> None:
    states = _states()
    turn = states.xy.copy()
    turn[1, 11:, 1] += np.linspace(0.0, 20.0, T - 11)  # the log turns away after the history
    states = replace(states, xy=turn)
    req = RolloutRequest(states=states, start_step=11, fixed_rows=np.array([0]), map=motion_map_from_features([]))
    out = ConstantVelocityPredictor().rollout(req).states
    np.testing.assert_allclose(out.xy[1, 11:, 1], 4.0)
    np.testing.assert_allclose(out.xy[1, 11:, 0], 20.0 + 5.0 * states.times[11:])


def test_motion_map_without_lanes_builds() -> None:
    mmap = motion_map_from_features([MapFeature("c", "crosswalk", np.zeros((4, 3)) + np.eye(4, 3))])
    assert len(mmap.lanes) == 0 and mmap.road_edges.shape == (0, 2, 2) and not mmap.context.has_lanes
    edge = MapFeature("e", "road_edge", np.array([[0.0, 0, 0], [5, 0, 0], [9, 1, 0]]))
    assert motion_map_from_features([edge]).road_edges.shape == (2, 2, 2)


def test_registry() -> None:
    assert {"log", "constant-velocity"} <= set(available_predictors())
    assert make_predictor("constant-velocity").name == "constant-velocity"
    with pytest.raises(KeyError, match="unknown predictor 'smart'"):
        make_predictor("smart")
    if "reactive" not in available_predictors():
        with pytest.raises(KeyError, match="reactive is not installed|'reactive' is not available"):
            make_predictor("reactive")


def test_rows_on_a_map_without_lanes() -> None:
    evaluation = R.real_rows([_scenario()], [ConstantVelocityPredictor(), LogReplayPredictor()])
    rows = {r["predictor"] or r["method"]: r for r in evaluation.rows}
    assert set(rows) == {"log", "constant-velocity"}  # the log replay is the log row
    log, cv = rows["log"], rows["constant-velocity"]
    assert (log["method"], log["predictor"], cv["method"], cv["predictor"]) == ("log", "", "full", "constant-velocity")
    assert log["refused"] == 0 and cv["refused"] == 0
    assert log["ade_3s"] is None and log["ade_8s"] is None
    assert cv["ade_3s"] == pytest.approx(0.0, abs=1e-9) and cv["ade_8s"] == pytest.approx(0.0, abs=1e-9)
    for row in (log, cv):
        assert row["failure"] == 0.0 and row["agent_collision"] == 0.0 and row["agent_offroad"] == 0.0
        assert row["progress"] == pytest.approx(1.0)
    assert set(evaluation.per_type["hand"]["constant-velocity"]) == {"vehicle"}  # "p" appears after the history
    table = motion_table(motion_rows(evaluation.rows))
    assert table.column_names == [n for n, _, _ in MOTION_COLUMNS] and table.num_rows == 2
    assert "| hand | log |  | 1 | 0 |" in MOTION_SPEC.render_markdown(table)


def test_a_collision_counts_per_scenario_and_per_agent() -> None:
    scenario = _scenario()
    states = scenario.states
    xy = states.xy.copy()
    xy[2, 11:] = xy[0, 11:]  # after the history "b" sits on the ego
    crash = replace(states, xy=xy)

    class Crasher:
        name = "crasher"

        def rollout(self, request):
            from simsplat_core.motion.predictor import Rollout

            return Rollout(crash, {}, self.name)

    rows = {r["predictor"] or r["method"]: r for r in R.real_rows([scenario], [Crasher()]).rows}
    row = rows["crasher"]
    assert row["collision_vehicle"] == 1.0 and row["failure"] == 1.0
    assert row["agent_collision"] == pytest.approx(2 / 4)  # the ego and "b"
    assert row["kinematic"] == 1.0  # "b" jumps 30 m in a step


def test_log_and_rollouts_are_scored_the_same_way() -> None:
    """An overlap already in the log counts for the log row and for a rollout that keeps it (no baseline)."""
    scenario = _scenario()
    xy = scenario.states.xy.copy()
    xy[2] = xy[0] + np.array([1.0, 0.0])  # "b" overlaps the ego over the whole log
    scenario = replace(scenario, states=replace(scenario.states, xy=xy))
    rows = {r["predictor"] or r["method"]: r for r in R.real_rows([scenario], [ConstantVelocityPredictor()]).rows}
    for name in ("log", "constant-velocity"):
        assert rows[name]["collision_vehicle"] == 1.0 and rows[name]["agent_collision"] == pytest.approx(2 / 4)


def test_rollouts_are_checked_on_the_steps_the_log_observed() -> None:
    """One object tracked under two ids that take turns: a predictor that fills both ids' gaps makes them
    overlap, but only on steps the log never observed, so neither the log nor the rollout collides."""
    scenario = _scenario()
    states = scenario.states
    xy, valid = states.xy.copy(), states.valid.copy()
    xy[2] = xy[1]  # "b" is "a" under another id ...
    valid[1, 1::2] = False  # ... observed on the even steps as "a"
    valid[2, 0::2] = False  # and on the odd ones as "b"
    scenario = replace(scenario, states=replace(states, xy=xy, valid=valid))

    class GapFiller:
        name = "gap-filler"

        def rollout(self, request):
            from simsplat_core.motion.predictor import Rollout

            filled = request.states.valid.copy()
            filled[1:3] = True
            return Rollout(replace(request.states, valid=filled), {}, self.name)

    rows = {r["predictor"] or r["method"]: r for r in R.real_rows([scenario], [GapFiller()]).rows}
    for name in ("log", "gap-filler"):
        assert rows[name]["collision_vehicle"] == 0.0 and rows[name]["agent_collision"] == 0.0
    # the same rollout scored on every step it fills in would collide
    filled = replace(scenario.states, valid=scenario.states.valid | np.isin(np.arange(4), [1, 2])[:, None])
    assert R.scenario_failures(filled, scenario.map.context).collision_vehicle


def test_resample_to_10_hz() -> None:
    fast = _states(hz=20.0, steps=2 * T)
    grid, resampled = R.on_step_grid(fast)
    assert resampled and grid.num_steps == T
    np.testing.assert_allclose(np.diff(grid.times), DT)
    np.testing.assert_allclose(grid.xy[1, :, 0], 20.0 + 5.0 * grid.times, atol=1e-9)
    assert not grid.valid[3, : T // 2].any() and grid.valid[3, T // 2 + 1:].all()
    same, again = R.on_step_grid(_states())
    assert not again and same.num_steps == T


def test_scenario_too_short_and_corrupt_records(tmp_path) -> None:
    bad = tmp_path / "bad.tfrecord"
    bad.write_bytes(b"\x10\x00\x00\x00\x00\x00\x00\x00garbage")
    with pytest.raises(CorruptLogError, match=str(bad)):
        R.load_real_log(bad)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        R.load_real_log(tmp_path / "missing.tfrecord")


def test_rate_outside_unit_interval_is_refused() -> None:
    row = {n: 0.0 for n, _, _ in MOTION_COLUMNS} | {"dataset": "d", "method": "m", "scenarios": 1, "failure": 2.0}
    with pytest.raises(ValueError, match="failure = 2.0"):
        motion_table([row])
    with pytest.raises(KeyError, match="no column 'ade_3s'"):
        motion_table([{k: v for k, v in row.items() if k != "ade_3s"} | {"failure": 0.0}])


@pytest.mark.parametrize("sample", ["waymo/motion_data_one_scenario.tfrecord", "av2/sensor-log-7fab2350"])
def test_real_samples(shared_data, sample: str) -> None:
    log = R.load_real_log(shared_data / sample)
    scenario = R.scenario_of_log(log)
    assert scenario.start_step == 11 and not scenario.resampled and len(scenario.map.lanes) > 100
    evaluation = R.real_rows([scenario], [ConstantVelocityPredictor()])
    rows = {r["predictor"] or r["method"]: r for r in evaluation.rows}
    log_row, cv = rows["log"], rows["constant-velocity"]
    assert log_row["ade_3s"] is None
    assert 0.05 < cv["ade_3s"] < cv["ade_8s"] < 5.0  # metres: the log's agents mostly keep their velocity
    assert cv["agent_collision"] >= log_row["agent_collision"]
    assert 0.0 <= log_row["agent_offroad"] < 0.5
    assert {"vehicle", "pedestrian"} <= set(evaluation.per_type[scenario.dataset]["constant-velocity"])
    if sample.startswith("waymo"):
        assert not scenario.map.context.has_drivable and scenario.map.road_edges.shape[0] > 1000
        assert log_row["agent_offroad"] < 0.1  # only parked cars in lots beyond the kerb
    motion_table(evaluation.rows)  # valid rows


def test_waymo_sample_without_lanes_still_builds(shared_data) -> None:
    log = R.load_real_log(shared_data / "waymo" / "motion_data_one_scenario.tfrecord")
    bare = replace(log, map_features=tuple(f for f in log.map_features if f.kind != "lane"))
    scenario = R.scenario_of_log(bare)
    assert len(scenario.map.lanes) == 0
    rows = R.real_rows([scenario], [ConstantVelocityPredictor()]).rows
    assert len(rows) == 2 and not math.isnan(rows[1]["ade_3s"])
