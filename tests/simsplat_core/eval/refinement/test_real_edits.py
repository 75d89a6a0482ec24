"""Scripted edits of real scenarios on a hand-made straight two-lane road (both lanes along +x): which vehicle is the
lead, the hard stop along the logged path, the stopped truck 30 m ahead, the jaywalker's timing, the edits that do
not apply (with reasons), and the ``"<dataset>+edits"`` rows of the motion table."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.eval.refinement import real_edits as E
from simsplat_core.eval.refinement.real import RealScenario
from simsplat_core.eval.refinement.synthetic import outcome_row
from simsplat_core.eval.refinement.table import motion_table, outcomes_table
from simsplat_core.motion.motion_map import motion_map_from_features
from simsplat_core.motion.reactive import ReactivePredictor
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.types import MapFeature

T = 91
DT = 0.1


def _road() -> list[MapFeature]:
    """Two 400 m lanes along +x (centres y = 0 and y = 3.5) between road edges at y = -1.75 and y = 5.25."""
    x = np.linspace(-100.0, 300.0, 81)

    def line(y: float) -> np.ndarray:
        return np.c_[x, np.full_like(x, y), np.zeros_like(x)]

    return [MapFeature("lane0", "lane", line(0.0)), MapFeature("lane1", "lane", line(3.5)),
            MapFeature("edge_r", "road_edge", line(-1.75)), MapFeature("edge_l", "road_edge", line(5.25)[::-1])]


def _states(with_leads: bool = True) -> AgentStates:
    """The ego at 10 m/s on lane 0; on lane 0 ahead: ``a`` (25 m) and ``b`` (50 m) at 10 m/s; ``c`` on lane 1."""
    t = np.arange(T) * DT
    rows = [(EGO_ID, 0.0, 0.0)] + ([("a", 25.0, 0.0), ("b", 50.0, 0.0)] if with_leads else []) + [("c", 30.0, 3.5)]
    xy = np.stack([np.c_[x0 + 10.0 * t, np.full(T, y)] for _, x0, y in rows])
    a = len(rows)
    return AgentStates(object_ids=tuple(r[0] for r in rows), categories=("vehicle",) * a, sources=("log",) * a,
                       node_ids=np.full(a, -1), frame_idx=np.arange(T), times=t, xy=xy, z=np.full((a, T), 0.8),
                       heading=np.zeros((a, T)), speed=np.full((a, T), 10.0), size=np.tile([4.5, 2.0, 1.6], (a, 1)),
                       valid=np.ones((a, T), bool))


def _scenario(with_leads: bool = True, features: list[MapFeature] | None = None) -> RealScenario:
    return RealScenario(dataset="hand", seq_id="road", states=_states(with_leads),
                        map=motion_map_from_features(_road() if features is None else features))


def test_vehicles_ahead_in_the_ego_lane() -> None:
    scenario = _scenario()
    ahead = E.vehicles_ahead(scenario)
    assert [scenario.states.object_ids[r] for r, _ in ahead] == ["a", "b"]  # "c" is in the other lane
    assert [d for _, d in ahead] == pytest.approx([25.0, 50.0])


def test_lead_brakes_hard_along_its_path() -> None:
    scenario = _scenario()
    edit = E.lead_brakes(scenario)
    assert edit.states is not None and edit.object_id == "a" and edit.reason == ""
    s, log = edit.states, scenario.states
    k = s.index("a")
    assert s.sources[k] == "edited" and s.sources.count("edited") == 1
    b = scenario.start_step + E.BRAKE_DELAY_STEPS
    np.testing.assert_allclose(s.xy[k, : b + 1], log.xy[k, : b + 1])
    np.testing.assert_allclose(s.xy[k, :, 1], 0.0, atol=1e-9)  # along its logged path
    decel = -np.diff(s.speed[k, b:]) / DT
    assert decel.max() <= E.BRAKE_DECEL_MPS2 + 1e-6 and decel.max() > 5.5  # hard braking, within 6 m/s^2
    assert s.speed[k, -1] == 0.0 and np.ptp(s.xy[k, -20:, 0]) < 1e-9  # stopped for good
    stop = s.xy[k, -1, 0] - log.xy[k, b, 0]
    assert 10.0**2 / (2 * E.BRAKE_DECEL_MPS2) < stop < 12.0  # v^2 / 2a plus the jerk ramps


def test_braking_profile() -> None:
    dist, speed = E.braking_distances(10.0, np.arange(0, 4.0, 0.1))
    assert dist[0] == 0.0 and speed[0] == pytest.approx(10.0)
    assert np.all(np.diff(dist) >= -1e-12) and speed[-1] == 0.0


def test_stopped_truck_30_m_ahead_in_the_ego_lane() -> None:
    scenario = _scenario(with_leads=False)
    edit = E.stopped_truck(scenario)
    assert edit.states is not None
    s = edit.states
    k = s.index(E.TRUCK_ID)
    ego_x = scenario.states.xy[0, scenario.start_step, 0]
    assert s.sources[k] == "inserted" and s.categories[k] == "vehicle"
    np.testing.assert_allclose(s.xy[k], np.tile([ego_x + 30.0, 0.0], (T, 1)), atol=1e-6)
    np.testing.assert_allclose(s.size[k], E.TRUCK_SIZE)
    assert s.valid[k].all() and not s.speed[k].any() and np.allclose(s.heading[k], 0.0)
    blocked = E.stopped_truck(_scenario())  # "a" drives through the spot during the history
    assert blocked.states is None and "is on the spot" in blocked.reason


def test_jaywalker_crosses_the_second_car_path() -> None:
    scenario = _scenario()
    edit = E.jaywalker(scenario)
    assert edit.states is not None and edit.object_id == "b"
    s = edit.states
    k = s.index(E.JAYWALKER_ID)
    t0 = scenario.start_step
    tc = t0 + 25
    assert s.categories[k] == "pedestrian" and s.sources[k] == "inserted"
    assert not s.valid[k, :t0].any() and s.valid[k, t0:].all()
    b_xy = scenario.states.xy[2, tc]
    np.testing.assert_allclose(s.xy[k, tc], b_xy, atol=1e-6)  # on the car's position 2.5 s after start
    np.testing.assert_allclose(s.xy[k, t0], b_xy + np.array([0.0, -E.WALK_MPS * 2.5]), atol=1e-6)  # kerb (right)
    step = np.linalg.norm(np.diff(s.xy[k, t0:], axis=0), axis=1) / DT
    np.testing.assert_allclose(step, E.WALK_MPS)
    only_a = RealScenario("hand", "road", _states().without(["b"]), motion_map_from_features(_road()))
    assert E.jaywalker(only_a).object_id == "a"  # no second car: the lead


def test_edits_that_do_not_apply_say_why() -> None:
    empty = _scenario(with_leads=False)
    for edit in (E.lead_brakes(empty), E.jaywalker(empty)):
        assert edit.states is None and "no moving vehicle ahead" in edit.reason
    no_lanes = _scenario(with_leads=False, features=[])
    assert "no lanes" in E.stopped_truck(no_lanes).reason
    assert [e.name for e in E.apply_edits(_scenario())] == list(E.EDITS)
    with pytest.raises(KeyError, match="unknown real edits"):
        E.apply_edits(_scenario(), ["teleport"])


def test_rows_per_mode_with_the_ego_reacting() -> None:
    evaluation = E.evaluate_real_edits([_scenario()], ReactivePredictor())
    assert evaluation.applied["road"]["lead_brakes"] == "" and "is on the spot" in evaluation.applied["road"][
        "stopped_truck"]
    rows = {r["method"]: r for r in evaluation.rows}
    assert list(rows) == ["none", "single-agent", "full"]
    assert {r["dataset"] for r in evaluation.rows} == {"hand+edits"}
    assert rows["none"]["predictor"] == "" and rows["full"]["predictor"] == "reactive"
    assert rows["none"]["scenarios"] == 2 and rows["none"]["refused"] == 0  # lead_brakes and jaywalker
    # without refinement the ego (on its log) runs into the braking lead
    none = {o.case.kind: o for o in evaluation.outcomes if o.mode == "none"}
    assert none["lead_brakes"].failures is not None and none["lead_brakes"].failures.collision_vehicle
    crash = "ego [log vehicle]: collision with a [edited vehicle]"
    assert any(d.startswith(crash) for d in none["lead_brakes"].details)
    full = {o.case.kind: o for o in evaluation.outcomes if o.mode == "full"}
    assert "ego" in full["lead_brakes"].refined  # the ego is predicted too (ego_reacts) and brakes
    assert full["lead_brakes"].failures is not None and not full["lead_brakes"].failures.collision_vehicle
    motion_table(evaluation.rows)  # valid rows
    table = outcomes_table([outcome_row(o, "hand+edits") for o in evaluation.outcomes])
    assert table.num_rows == 6 and set(table["source"].to_pylist()) == {"real-edit"}
