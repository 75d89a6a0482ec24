"""Windows of real logs and the stall diagnosis, on hand-built scenes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.eval.refinement.diagnosis import STALLS_SPEC, diagnose, stalls_table
from simsplat_core.eval.refinement.real import RealScenario, real_rows
from simsplat_core.eval.refinement.windows import WINDOW_STEPS, slice_steps, window_starts, windows_of
from simsplat_core.motion.predictor import RolloutRequest
from simsplat_core.motion.reactive import RULE_FREE, ReactivePredictor
from simsplat_core.scenario.agents import EGO_ID
from tests.simsplat_core.motion.scenes import CAR, START, TIMES, T, road, states, track


def test_window_starts_cover_the_log_at_the_stride() -> None:
    assert window_starts(156, 10) == [0, 10, 20, 30, 40, 50, 60]
    assert window_starts(110, 10) == [0, 10]
    assert window_starts(91, 10) == [0]
    assert window_starts(50, 10) == [0]  # shorter than a window: the whole log
    with pytest.raises(ValueError, match="stride"):
        window_starts(100, 0)


def test_slice_restarts_time_and_drops_absent_agents() -> None:
    valid = {"late": np.arange(T) >= 60}
    st = states([(EGO_ID, "vehicle", track(10.0 * TIMES, 0.0), CAR), ("late", "vehicle", track(5.0 * TIMES, 3.5), CAR)],
                valid)
    cut = slice_steps(st, 10, 50)
    assert cut.num_steps == 40 and cut.times[0] == 0.0
    assert cut.object_ids == (EGO_ID,)
    assert np.allclose(cut.xy[0], st.xy[0, 10:50])


def test_a_long_log_gives_one_scenario_per_window_and_pooled_rows() -> None:
    n = 121
    times = np.arange(n) * 0.1
    base = states([(EGO_ID, "vehicle", track(10.0 * TIMES, 0.0), CAR),
                   ("car", "vehicle", track(8.0 * TIMES, 3.5), CAR)])
    st = dataclasses.replace(base, frame_idx=np.arange(n), times=times, xy=np.stack([
        np.stack([10.0 * times, np.zeros(n)], 1), np.stack([8.0 * times, np.full(n, 3.5)], 1)]),
        z=np.zeros((2, n)), heading=np.zeros((2, n)), speed=np.stack([np.full(n, 10.0), np.full(n, 8.0)]),
        valid=np.ones((2, n), bool))
    scenario = RealScenario("test", "log", st, road())
    wins = windows_of(scenario, stride=10)
    assert [w.seq_id for w in wins] == ["log@0", "log@10", "log@20", "log@30"]
    assert all(w.states.num_steps == WINDOW_STEPS for w in wins)
    rows = real_rows(wins, [ReactivePredictor()]).rows
    assert {r["method"]: r["scenarios"] for r in rows} == {"log": 4, "full": 4}


def _stop_scene(blocker_category: str, blocker_size: tuple[float, float, float]) -> RealScenario:
    """A car driving 10 m/s in lane 0 and a parked obstacle at x = 35 across both lanes that the log drives
    through."""
    st = states([(EGO_ID, "vehicle", track(np.full(T, -200.0), 3.5), CAR),
                 ("car", "vehicle", track(10.0 * TIMES, 0.0), CAR),
                 ("block", blocker_category, track(np.full(T, 35.0), 1.75), blocker_size)])
    return RealScenario("test", "stop", st, road())


@pytest.mark.parametrize(("category", "size", "named"), [("vehicle", (2.0, 8.0, 3.0), "block (parked vehicle)"),
                                                          ("static", (2.0, 8.0, 1.0), "block (kerb obstacle)")])
def test_a_stalled_agent_names_its_blocker_rule_and_distance(category: str, size: tuple[float, float, float],
                                                              named: str) -> None:
    scenario = _stop_scene(category, size)
    req = RolloutRequest(scenario.states, START, np.array([0]), scenario.map)
    rollout, trace = ReactivePredictor().traced_rollout(req)
    stalls = diagnose(scenario.states, rollout, trace, START, dataset="test", seq_id="stop")
    assert [s.object_id for s in stalls] == ["car"]
    s = stalls[0]
    assert s.rule == "leader" and s.blocker == named
    assert 0.0 <= s.distance_m < 5.0 and s.progress < 0.8
    table = stalls_table(stalls)
    assert table.schema == STALLS_SPEC.schema and table.num_rows == 1


def test_an_agent_that_moves_like_its_log_is_not_listed() -> None:
    st = states([(EGO_ID, "vehicle", track(np.full(T, -200.0), 3.5), CAR),
                 ("car", "vehicle", track(10.0 * TIMES, 0.0), CAR)])
    req = RolloutRequest(st, START, np.array([0]), road())
    rollout, trace = ReactivePredictor().traced_rollout(req)
    assert diagnose(st, rollout, trace, START) == []
    assert (trace.rule[0, START:] == RULE_FREE).all() and not np.isfinite(trace.gap[0, START:]).any()
