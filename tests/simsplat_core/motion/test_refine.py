"""Refinement modes: which rows a predictor may move, where prediction starts, sources of the result."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.motion.predictor import MotionMap, Rollout, RolloutRequest
from simsplat_core.motion.refine import edit_start_step, fixed_rows, refine
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import collision_steps

T = 20


def _states(sources: list[str], categories: list[str] | None = None) -> AgentStates:
    a = len(sources)
    categories = categories or ["vehicle"] * a
    xy = np.zeros((a, T, 2))
    xy[:, :, 0] = np.arange(T)[None] * 1.0 + 10.0 * np.arange(a)[:, None]
    xy[:, :, 1] = 3.5 * np.arange(a)[:, None]
    return AgentStates(object_ids=("ego", *(f"a{k}" for k in range(1, a))), categories=tuple(categories),
                       sources=tuple(sources), node_ids=np.arange(a, dtype=np.int64) - 1,
                       frame_idx=np.arange(T), times=np.arange(T) * 0.1, xy=xy, z=np.zeros((a, T)),
                       heading=np.zeros((a, T)), speed=np.full((a, T), 10.0), size=np.tile([4.5, 2.0, 1.5], (a, 1)),
                       valid=np.ones((a, T), bool))


class _Nudge:
    """Test double: moves every free agent 1 m to the left from ``start_step`` on and marks it refined; with
    ``only_edited`` only when the scenario holds an edited agent (a predictor whose free agents react to the edit),
    otherwise always (a predictor whose error against the log has nothing to do with the edit)."""

    name = "nudge"

    def __init__(self, only_edited: bool = True) -> None:
        self.requests: list[RolloutRequest] = []
        self.only_edited = only_edited

    def rollout(self, request: RolloutRequest) -> Rollout:
        self.requests.append(request)
        s = request.states
        xy, sources = s.xy.copy(), list(s.sources)
        if self.only_edited and not {"edited", "inserted"} & set(s.sources):
            return Rollout(s, {}, self.name)
        for r in request.free_rows:
            xy[r, request.start_step:, 1] += 1.0
            sources[r] = "refined"
        return Rollout(dataclasses.replace(s, xy=xy, sources=tuple(sources)), {}, self.name)


def _map() -> MotionMap:
    return MotionMap(LaneGraph.from_features([]), MapContext.from_features([]))


def test_fixed_rows_per_mode() -> None:
    states = _states(["log", "edited", "log", "inserted", "log"], ["vehicle", "vehicle", "pedestrian", "vehicle",
                                                                     "static"])
    assert fixed_rows(states, "none").tolist() == [0, 1, 2, 3, 4]
    assert fixed_rows(states, "full").tolist() == [0, 1, 3, 4]  # ego, the edit, static objects
    assert fixed_rows(states, "single-agent").tolist() == [0, 2, 4]  # only the edited agents are free
    with pytest.raises(ValueError, match="refinement mode"):
        fixed_rows(states, "partial")


def test_start_step_is_where_the_edit_departs_from_the_log() -> None:
    log = _states(["log", "log", "log"])
    edited = dataclasses.replace(log, sources=("log", "edited", "log"), xy=log.xy.copy())
    edited.xy[1, 7:, 0] += 2.0
    assert edit_start_step(edited, log) == 7
    inserted = log.with_agent("new", "vehicle", "inserted", xy=np.zeros((T, 2)), heading=np.zeros(T),
                              speed=np.zeros(T), valid=np.ones(T, bool), size=(4.5, 2.0, 1.5))
    assert edit_start_step(inserted, log) == 1  # present from the first frame: react from the first step


def test_full_refinement_moves_only_free_agents_and_marks_them() -> None:
    log = _states(["log", "log", "log", "log"])
    edited = dataclasses.replace(log, sources=("log", "edited", "log", "log"), xy=log.xy.copy())
    edited.xy[1, 5:, 0] += 1.0
    nudge = _Nudge()
    out = refine(edited, _map(), nudge, "full", original=log)
    assert out.start_step == 5 and nudge.requests[0].start_step == 5
    assert out.refined_ids == ("a2", "a3")
    np.testing.assert_array_equal(out.states.xy[:2], edited.xy[:2])  # ego and the edited agent untouched
    assert out.states.sources[1] == "edited"


def test_full_refinement_keeps_the_log_of_agents_the_edit_does_not_affect() -> None:
    log = _states(["log", "log", "log"])
    edited = dataclasses.replace(log, sources=("log", "edited", "log"), xy=log.xy.copy())
    edited.xy[1, 5:, 0] += 1.0
    nudge = _Nudge(only_edited=False)  # moves free agents with or without the edit: not a reaction
    out = refine(edited, _map(), nudge, "full", original=log)
    assert len(nudge.requests) == 2  # the edited scenario and the unedited one
    assert out.refined_ids == () and out.states.sources == edited.sources
    np.testing.assert_array_equal(out.states.xy, edited.xy)


def test_single_agent_keeps_the_edited_source_and_none_changes_nothing() -> None:
    log = _states(["log", "log", "log"])
    edited = dataclasses.replace(log, sources=("log", "edited", "log"))
    single = refine(edited, _map(), _Nudge(), "single-agent", original=log)
    assert single.states.sources == ("log", "edited", "log")
    assert single.states.xy[1, -1, 1] == pytest.approx(edited.xy[1, -1, 1] + 1.0)
    none = refine(edited, _map(), None, "none", original=log)
    assert none.states is edited and none.refined_ids == ()
    with pytest.raises(ValueError, match="needs a motion predictor"):
        refine(edited, _map(), None, "full", original=log)


def test_ego_reacts_frees_the_ego_in_full_mode_only() -> None:
    states = _states(["log", "edited", "log", "log"], ["vehicle", "vehicle", "vehicle", "static"])
    assert fixed_rows(states, "full", ego_reacts=True).tolist() == [1, 3]  # the edit and static objects
    assert fixed_rows(states, "single-agent", ego_reacts=True).tolist() == [0, 2, 3]  # the ego is not edited
    assert fixed_rows(states, "none", ego_reacts=True).tolist() == [0, 1, 2, 3]
    log = _states(["log", "log", "log", "log"], ["vehicle", "vehicle", "vehicle", "static"])
    edited = dataclasses.replace(log, sources=states.sources)
    fixed_ego = refine(edited, _map(), _Nudge(), "full", original=log, start_step=3)
    assert "ego" not in fixed_ego.refined_ids
    free_ego = refine(edited, _map(), _Nudge(), "full", original=log, start_step=3, ego_reacts=True)
    assert free_ego.refined_ids == ("ego", "a2")
    assert free_ego.states.xy[0, -1, 1] == pytest.approx(log.xy[0, -1, 1] + 1.0)


class _StopAll:
    """Test double: every free agent stops where it is at step 3, with the edit or without (a predictor error
    that has nothing to do with the edit)."""

    name = "stop-all"

    def rollout(self, request: RolloutRequest) -> Rollout:
        s = request.states
        xy, sources = s.xy.copy(), list(s.sources)
        for r in request.free_rows:
            xy[r, 3:] = xy[r, 3]
            sources[r] = "refined"
        return Rollout(dataclasses.replace(s, xy=xy, sources=tuple(sources)), {}, self.name)


def test_an_agent_whose_log_runs_into_a_kept_rollout_keeps_its_rollout_too() -> None:
    """a1 (edited) stops at step 5; a2 follows it 10 m behind, a3 10 m behind a2, all at 10 m/s. Both rollouts
    stop a2 and a3 alike, with or without the edit: a2 keeps its rollout because its log runs into a1, and then
    a3 must keep its own, because its log runs into a2's rollout (not into a2's log)."""
    log = _states(["log", "log", "log", "log"])
    log.xy[0, :, 1] = -50.0  # the ego, out of the way
    for k, x0 in ((1, 20.0), (2, 10.0), (3, 0.0)):
        log.xy[k, :, 0] = x0 + np.arange(T)
        log.xy[k, :, 1] = 0.0
    edited = dataclasses.replace(log, sources=("log", "edited", "log", "log"), xy=log.xy.copy())
    edited.xy[1, 5:, 0] = edited.xy[1, 5, 0]
    out = refine(edited, _map(), _StopAll(), "full", original=log)
    assert set(out.refined_ids) == {"a2", "a3"}
    assert not collision_steps(out.states, [2, 3]).pairs.any()


def test_an_agent_that_appears_later_and_would_run_into_the_edit_is_driven_from_when_it_appears() -> None:
    """a1 (edited) stops at step 5 on a straight lane; a2 appears 15 m behind it at step 8, driving 10 m/s along
    the lane, and its log runs into a1. The reactive model cannot drive a2 from step 5 (it is not there yet), so it
    is driven from the step after it appears: it brakes behind a1 instead of replaying into it."""
    from simsplat_core.motion.reactive import ReactivePredictor
    from simsplat_core.types import MapFeature

    steps = 60
    xs = np.linspace(-20.0, 200.0, 45)
    lane = MapFeature("lane_1", "lane", np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)], 1))
    motion_map = MotionMap(LaneGraph.from_features([lane]), MapContext.from_features([lane]))
    t = np.arange(steps) * 0.1
    xy = np.zeros((3, steps, 2))
    xy[0, :, 1] = -50.0  # the ego, out of the way
    xy[1, :, 0] = 40.0 + 10.0 * t
    xy[2, :, 0] = 40.0 - 15.0 + 10.0 * (t - 0.8)
    valid = np.ones((3, steps), bool)
    valid[2, :8] = False
    log = AgentStates(object_ids=("ego", "a1", "a2"), categories=("vehicle",) * 3, sources=("log",) * 3,
                      node_ids=np.array([-1, 0, 1]), frame_idx=np.arange(steps), times=t, xy=xy,
                      z=np.zeros((3, steps)), heading=np.zeros((3, steps)), speed=np.full((3, steps), 10.0),
                      size=np.tile([4.5, 2.0, 1.5], (3, 1)), valid=valid)
    edited = dataclasses.replace(log, sources=("log", "edited", "log"), xy=log.xy.copy(), speed=log.speed.copy())
    edited.xy[1, 5:, 0] = edited.xy[1, 5, 0]
    edited.speed[1, 5:] = 0.0
    assert collision_steps(edited, [1]).pairs.any()  # replaying its log, a2 drives into the stopped car
    out = refine(edited, motion_map, ReactivePredictor(), "full", original=log)
    assert "a2" in out.refined_ids and "a2" not in out.replayed
    np.testing.assert_array_equal(out.states.valid[2], valid[2])  # it still appears when it did
    np.testing.assert_allclose(out.states.xy[2, :9], edited.xy[2, :9])  # its log until it is driven
    assert not collision_steps(out.states, [1, 2]).pairs.any()
