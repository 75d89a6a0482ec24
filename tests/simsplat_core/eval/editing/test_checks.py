"""State checks on hand-made edited agents: each passes the edit it was made for and fails others."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.eval.editing.checks import Verdict, _check_crossing_spot, check_refusal, check_states, measured_speed
from simsplat_core.eval.editing.intents import (
    EGO,
    AssetIntent,
    EditIntent,
    MotionIntent,
    PlacementIntent,
    SpeedWords,
)
from simsplat_core.eval.editing.observation import EditObservation, state_changes
from simsplat_core.eval.editing.plans import _ego_lane_spot, _free
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.world.paths import route


@pytest.fixture(scope="module")
def truth(truths) -> SceneTruth:
    return truths[1]


@pytest.fixture(scope="module")
def before(truth) -> AgentStates:
    return AgentStates.from_log(truth.log, truth.node_of_object)


def _cruiser(truth: SceneTruth) -> str:
    """A vehicle driving at a steady speed >= 5 m/s."""
    for a in truth.world.agents:
        if a.category == "vehicle" and a.traj["speed"][0] >= 5 and np.std(a.traj["speed"]) < 0.1:
            return a.object_id
    raise AssertionError("no steady vehicle in the scene")


def _along_path(truth, before, oid, s_of_t, node_id=None):
    """``before`` with ``oid`` driving its own path at arc lengths ``s_of_t(t)`` (relative to its start)."""
    agent = truth.agent(oid)
    path = agent.motion.path
    s = agent.traj["s"][0] + s_of_t(before.times)
    row = before.index(oid)
    xy, heading = path.position(s), path.heading(s)
    speed = np.gradient(s, before.times)
    return before.with_agent(oid, "vehicle", "edited", xy=xy, heading=heading, speed=speed,
                             valid=np.ones(before.num_steps, bool), size=before.size[row],
                             node_id=int(before.node_ids[row]) if node_id is None else node_id)


def _obs(before, after) -> EditObservation:
    return EditObservation(None, "", before, after)


def test_measured_speed_comes_from_positions(truth, before) -> None:
    oid = _cruiser(truth)
    after = _along_path(truth, before, oid, lambda t: 6.0 * t)
    row = after.index(oid)
    lying = after.with_agent(oid, "vehicle", "edited", xy=after.xy[row], heading=after.heading[row],
                             speed=np.full(after.num_steps, 20.0), valid=after.valid[row], size=after.size[row],
                             node_id=int(after.node_ids[row]))
    assert np.allclose(measured_speed(lying, row)[5:-5], 6.0, atol=0.05)


def test_remove_exactly_the_targets(truth, before) -> None:
    intent = EditIntent("remove", ("veh_01",))
    assert check_states(truth, intent, _obs(before, before.without(["veh_01"]))).passed
    wrong = check_states(truth, intent, _obs(before, before.without(["veh_02"])))
    assert not wrong.passed and "removed ['veh_02']" in wrong.reason
    extra = check_states(truth, intent, _obs(before, before.without(["veh_01", "veh_02"])))
    assert not extra.passed
    group = EditIntent("remove", ("veh_01", "veh_02"), group=True)
    assert check_states(truth, group, _obs(before, before.without(["veh_01", "veh_02"]))).passed
    assert not check_states(truth, group, _obs(before, before.without(["veh_01"]))).passed


def test_speed_reached_on_the_same_path(truth, before) -> None:
    oid = _cruiser(truth)
    v0 = float(truth.agent(oid).traj["speed"][0])
    target = v0 + 3.0
    # accelerate at 2 m/s^2 from v0 to target, then hold
    t_acc = 3.0 / 2.0

    def s_of_t(t):
        return np.where(t < t_acc, v0 * t + t * t, v0 * t_acc + t_acc**2 + target * (t - t_acc))

    after = _along_path(truth, before, oid, s_of_t)
    intent = EditIntent("modify", (oid,), motion=MotionIntent(speed_mps=target, speed=SpeedWords("absolute", target,
                                                                                                 "m/s")))
    ok = check_states(truth, intent, _obs(before, after))
    assert ok.passed, ok.reason
    assert ok.measured["speed_mps"] == pytest.approx(target, abs=0.3)
    too_slow = EditIntent("modify", (oid,), motion=MotionIntent(speed_mps=target + 3.0))
    assert "speed" in check_states(truth, too_slow, _obs(before, after)).reason
    unchanged = check_states(truth, intent, _obs(before, before))
    assert not unchanged.passed and "changed the trajectory of nothing" in unchanged.reason


def test_other_agents_may_react_but_not_leave_their_path(truth, before) -> None:
    oid = _cruiser(truth)
    after = _along_path(truth, before, oid, lambda t: 0.5 * truth.agent(oid).traj["speed"][0] * t)
    other = next(a.object_id for a in truth.world.agents if a.category == "vehicle" and a.object_id != oid
                 and float(np.ptp(a.traj["s"])) > 5.0)
    row = after.index(other)
    moved = after.with_agent(other, "vehicle", "edited", xy=after.xy[row] + 6.0, heading=after.heading[row],
                             speed=after.speed[row], valid=after.valid[row], size=after.size[row],
                             node_id=int(after.node_ids[row]))
    # a reaction: the other vehicle slows down along its own logged path (it lags 10 steps behind its log)
    lag = np.concatenate([np.repeat(after.xy[row, :1], 10, axis=0), after.xy[row, :-10]])
    reacted = after.with_agent(other, "vehicle", "refined", xy=lag, heading=after.heading[row],
                               speed=after.speed[row], valid=after.valid[row], size=after.size[row],
                               node_id=int(after.node_ids[row]))
    half = 0.5 * float(truth.agent(oid).traj["speed"][0])
    intent = EditIntent("modify", (oid,), motion=MotionIntent(speed_mps=half))
    assert check_states(truth, intent, _obs(before, after)).passed
    assert check_states(truth, intent, _obs(before, reacted)).passed
    assert other in check_states(truth, intent, _obs(before, moved)).reason


def test_stop_and_stop_by_time(truth, before) -> None:
    oid = _cruiser(truth)
    v0 = float(truth.agent(oid).traj["speed"][0])
    decel = v0 / 2.0  # standing still after 2 s

    def s_of_t(t):
        tc = np.minimum(t, 2.0)
        return v0 * tc - 0.5 * decel * tc * tc

    after = _along_path(truth, before, oid, s_of_t)
    stop = EditIntent("modify", (oid,), motion=MotionIntent(stop=True))
    result = check_states(truth, stop, _obs(before, after))
    assert result.passed, result.reason
    assert result.measured["stopped_at_s"] == pytest.approx(2.0, abs=0.4)
    assert check_states(truth, EditIntent("modify", (oid,), motion=MotionIntent(stop=True, stop_by_s=2.5)),
                        _obs(before, after)).passed
    late = check_states(truth, EditIntent("modify", (oid,), motion=MotionIntent(stop=True, stop_by_s=0.5)),
                        _obs(before, after))
    assert not late.passed and "asked by 0.5" in late.reason
    slower = _along_path(truth, before, oid, lambda t: 0.6 * v0 * t)
    assert not check_states(truth, stop, _obs(before, slower)).passed
    hard = check_states(truth, EditIntent("modify", (oid,), motion=MotionIntent(longitudinal="brake_hard")),
                        _obs(before, after))
    assert hard.passed == (decel >= 4.0), hard.reason


def test_turn_checked_by_the_auto_labeller(truth, before, prompts) -> None:
    turn = next(p for p in prompts if p.kind == "vehicle_turn" and p.seq_id == truth.seq_id)
    oid, side = turn.intent.targets[0], turn.intent.motion.turn
    agent = truth.agent(oid)
    pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
    path = route(truth.layout, pos.arm, pos.lane, side)
    s0 = path.project(agent.traj["xy"][0])
    s = s0 + float(agent.traj["speed"][0]) * before.times
    row = before.index(oid)
    after = before.with_agent(oid, "vehicle", "edited", xy=path.position(s), heading=path.heading(s),
                              speed=np.full(before.num_steps, agent.traj["speed"][0]), valid=before.valid[row],
                              size=before.size[row], node_id=int(before.node_ids[row]))
    ok = check_states(truth, turn.intent, _obs(before, after))
    assert ok.passed, ok.reason
    other = "right" if side == "left" else "left"
    wrong = check_states(truth, EditIntent("modify", (oid,), motion=MotionIntent(turn=other)), _obs(before, after))
    assert not wrong.passed and f"turning_{other}" in wrong.reason


def test_lane_change_checked_by_the_auto_labeller(truth, before, prompts) -> None:
    change = next(p for p in prompts if p.kind == "vehicle_lane_change" and p.seq_id == truth.seq_id)
    oid, side = change.intent.targets[0], change.intent.motion.lane_change
    row = before.index(oid)
    h = before.heading[row]
    left = np.stack([-np.sin(h), np.cos(h)], axis=1)
    w = np.clip((before.times - 0.5) / 2.5, 0, 1)
    shift = (3.0 * w * w - 2.0 * w**3) * truth.layout.lane_w_h * (1 if side == "left" else -1)
    after = before.with_agent(oid, "vehicle", "edited", xy=before.xy[row] + shift[:, None] * left, heading=h,
                              speed=before.speed[row], valid=before.valid[row], size=before.size[row],
                              node_id=int(before.node_ids[row]))
    ok = check_states(truth, change.intent, _obs(before, after))
    assert ok.passed, ok.reason
    other = EditIntent("modify", (oid,), motion=MotionIntent(lane_change="right" if side == "left" else "left"))
    assert not check_states(truth, other, _obs(before, after)).passed


def test_delay_stands_then_follows_the_path(truth, before) -> None:
    oid = _cruiser(truth)
    v0 = float(truth.agent(oid).traj["speed"][0])
    delayed = _along_path(truth, before, oid, lambda t: v0 * np.maximum(t - 1.5, 0.0))
    intent = EditIntent("modify", (oid,), motion=MotionIntent(delay_s=1.5))
    ok = check_states(truth, intent, _obs(before, delayed))
    assert ok.passed, ok.reason
    slow_start = _along_path(truth, before, oid, lambda t: 0.5 * v0 * t)
    assert "before the delay" in check_states(truth, intent, _obs(before, slow_start)).reason


def _insert(before, oid, category, xy, heading, size, speed=0.0):
    n = before.num_steps
    xy = np.broadcast_to(np.asarray(xy, float), (n, 2)).copy() if np.ndim(xy) == 1 else xy
    return before.with_agent(oid, category, "inserted", xy=xy, heading=np.full(n, heading),
                             speed=np.full(n, speed), valid=np.ones(n, bool), size=size, node_id=999)


def test_insert_in_the_ego_lane_at_the_said_distance(truth, before) -> None:
    d = next(d for d in np.arange(8.0, 30.0) if _free(truth, *_ego_lane_spot(truth, d)))
    spot, h = _ego_lane_spot(truth, d)
    intent = EditIntent("insert", asset=AssetIntent("vehicle", "sedan", "red"),
                        placement=PlacementIntent("in_lane", EGO, d, "same"))
    ok = check_states(truth, intent, _obs(before, _insert(before, "new_0", "vehicle", spot, h, (4.6, 1.8, 1.45))))
    assert ok.passed, ok.reason
    far = spot + 10.0 * np.array([np.cos(h), np.sin(h)])
    assert "not in the same lane" in check_states(
        truth, intent, _obs(before, _insert(before, "new_0", "vehicle", far, h, (4.6, 1.8, 1.45)))).reason
    left = spot + truth.layout.lane_w_h * np.array([-np.sin(h), np.cos(h)])
    assert not check_states(truth, intent, _obs(before, _insert(before, "new_0", "vehicle", left, h,
                                                                (4.6, 1.8, 1.45)))).passed
    side = EditIntent("insert", asset=AssetIntent("vehicle"), placement=PlacementIntent("in_lane", EGO, d, "left"))
    assert check_states(truth, side, _obs(before, _insert(before, "new_0", "vehicle", left, h,
                                                          (4.6, 1.8, 1.45)))).passed
    wrong_kind = check_states(truth, intent, _obs(before, _insert(before, "new_0", "pedestrian", spot, h,
                                                                  (0.6, 0.6, 1.7))))
    assert "asked for a vehicle" in wrong_kind.reason
    two = _insert(_insert(before, "new_1", "vehicle", far, h, (4.6, 1.8, 1.45)), "new_0", "vehicle", spot, h,
                  (4.6, 1.8, 1.45))
    assert "added 2 agents" in check_states(truth, intent, _obs(before, two)).reason


def test_insert_behind_an_anchor_and_overlaps(truth, before) -> None:
    anchor = "veh_05"  # the stopped pickup
    agent = truth.agent(anchor)
    h = float(agent.traj["heading"][0])
    back = agent.traj["xy"][0] - (agent.size[0] / 2 + 6.0 + 2.3) * np.array([np.cos(h), np.sin(h)])
    intent = EditIntent("insert", asset=AssetIntent("vehicle"), placement=PlacementIntent("behind", anchor, 6.0))
    ok = check_states(truth, intent, _obs(before, _insert(before, "new_0", "vehicle", back, h, (4.6, 1.8, 1.45))))
    assert ok.passed, ok.reason
    front = agent.traj["xy"][0] + (agent.size[0] / 2 + 8.3) * np.array([np.cos(h), np.sin(h)])
    assert "in front of the anchor" in check_states(
        truth, intent, _obs(before, _insert(before, "new_0", "vehicle", front, h, (4.6, 1.8, 1.45)))).reason
    on_top = check_states(truth, intent, _obs(before, _insert(before, "new_0", "vehicle", agent.traj["xy"][0], h,
                                                              (4.6, 1.8, 1.45))))
    assert "overlapping ['veh_05']" in on_top.reason


def test_insert_on_the_sidewalk_ahead(truth, before) -> None:
    ego = truth.road_position(truth.ego_xy[0], float(truth.ego_heading[0]))
    layout = truth.layout
    spot = layout.arm_point(ego.arm, ego.along - 12.0, layout.half_width(ego.arm) + layout.sidewalk_w / 2)
    intent = EditIntent("insert", asset=AssetIntent("pedestrian", upper="red"),
                        placement=PlacementIntent("on_sidewalk", EGO, 12.0))
    ok = check_states(truth, intent, _obs(before, _insert(before, "new_0", "pedestrian", spot, 0.0, (0.6, 0.6, 1.7))))
    assert ok.passed, ok.reason
    road = layout.arm_point(ego.arm, ego.along - 12.0, 1.0)
    assert "asked for the sidewalk" in check_states(
        truth, intent, _obs(before, _insert(before, "new_0", "pedestrian", road, 0.0, (0.6, 0.6, 1.7)))).reason


def test_refusals(before) -> None:
    intent = EditIntent("remove", expected_refusals=("not_found",), structured=False)
    assert check_refusal(intent, EditObservation.refusal("not_found", "no purple bus")).passed
    odd = check_refusal(intent, EditObservation.refusal("unsupported", "?"))
    assert odd.passed and "unexpected reason" in odd.reason
    assert not check_refusal(intent, EditObservation(None, "removed node 3", before, before)).passed
    feasible = EditIntent("remove", ("veh_01",))
    assert "refused" in check_states(None, feasible, EditObservation.refusal("not_found", "nope")).reason  # type: ignore[arg-type]


def test_state_changes_measures_redrawn_and_moved(before) -> None:
    row = before.index("veh_01")
    redrawn = before.with_agent("veh_01", "vehicle", "edited", xy=before.xy[row], heading=before.heading[row],
                                speed=before.speed[row], valid=before.valid[row], size=(11.5, 2.5, 3.1), node_id=777)
    changes = state_changes(before, redrawn)
    assert changes.redrawn == ("veh_01",) and changes.moved == () and changes.removed == ()


def test_a_static_kind_needs_its_box(truth, before) -> None:
    spot, h = _ego_lane_spot(truth, 8.0)
    intent = EditIntent("insert", asset=AssetIntent("static", "barrel", "orange"),
                        placement=PlacementIntent("in_lane", EGO, 8.0, "same"))
    barrel = check_states(truth, intent, _obs(before, _insert(before, "new_0", "static", spot, h, (0.6, 0.6, 1.0))))
    assert "a barrel is" not in barrel.reason
    cone = check_states(truth, intent, _obs(before, _insert(before, "new_0", "static", spot, h, (0.42, 0.42, 0.72))))
    assert not cone.passed and "a barrel is 0.60 x 0.60 x 1.00 m" in cone.reason


def test_a_speed_up_runs_on_past_a_log_that_ends_standing(truth, before) -> None:
    """A log that brakes to a halt repeats its last point; a faster edit carries on straight past that end (the
    way the log faced) and keeps its path, while one that swerves off it there does not."""
    oid = _cruiser(truth)
    row = before.index(oid)
    v0 = float(truth.agent(oid).traj["speed"][0])
    heading = float(before.heading[row, 0])
    direction = np.array([np.cos(heading), np.sin(heading)])
    left = np.array([-direction[1], direction[0]])
    t = before.times - before.times[0]

    def straight(s, side):
        xy = before.xy[row, 0] + s[:, None] * direction + side[:, None] * left
        return before.with_agent(oid, "vehicle", "edited", xy=xy, heading=np.full(len(s), heading),
                                 speed=np.gradient(s, before.times), valid=np.ones(len(s), bool),
                                 size=before.size[row], node_id=int(before.node_ids[row]))

    stop_s = v0 * t[len(t) // 3]
    halting = straight(np.minimum(v0 * t, stop_s), np.zeros(len(t)))  # drives, then stands where it stopped
    s_fast = v0 * t + t * t
    intent = EditIntent("modify", (oid,), motion=MotionIntent(longitudinal="accelerate"))
    ok = check_states(truth, intent, _obs(halting, straight(s_fast, np.zeros(len(t)))))
    assert ok.passed, ok.reason
    swerving = straight(s_fast, np.where(s_fast > stop_s + 5.0, 3.0, 0.0))
    assert "leaves its path" in check_states(truth, intent, _obs(halting, swerving)).reason


def test_a_faster_walker_may_step_aside_only_to_pass_someone(truth, before) -> None:
    """A walker told to walk faster keeps its path within half a metre, except for a step aside of about a metre
    while another pedestrian is close by (passing them); the same step with nobody about leaves its path."""
    walkers = [a for a in truth.world.agents if a.category == "pedestrian" and a.object_id in before.object_ids
               and before.valid[before.index(a.object_id)].all() and float(np.min(a.traj["speed"])) > 0.5]
    walker, other = walkers[0], next(a for a in truth.world.agents if a.category == "pedestrian"
                                     and a is not walkers[0] and a.object_id in before.object_ids)
    row, far = before.index(walker.object_id), before.index(other.object_id)
    t = before.times - before.times[0]
    target = 1.25 * float(walker.traj["speed"][0])
    s = walker.traj["s"][0] + target * t
    heading = walker.motion.path.heading(s)
    left = np.stack([-np.sin(heading), np.cos(heading)], axis=1)
    bump = np.clip(1.0 - np.abs(t - t[-1] / 3.0) / 1.0, 0.0, 1.0)  # [T] up to 1 m aside around a third of the way
    xy = walker.motion.path.position(s) + bump[:, None] * left
    after = before.with_agent(walker.object_id, "pedestrian", "edited", xy=xy, heading=heading,
                              speed=np.gradient(s, before.times), valid=np.ones(len(t), bool), size=before.size[row],
                              node_id=int(before.node_ids[row]))
    intent = EditIntent("modify", (walker.object_id,), motion=MotionIntent(
        speed_mps=target, speed=SpeedWords("absolute", target, "m/s")))

    def with_other_at(spot: np.ndarray) -> tuple[AgentStates, AgentStates]:
        states = []
        for base in (before, after):
            other_xy = base.xy.copy()
            other_xy[far] = spot  # standing there, in the log and after the edit alike
            valid = base.valid.copy()
            valid[far] = True
            states.append(dataclasses.replace(base, xy=other_xy, valid=valid,
                                              speed=np.where(np.arange(base.num_agents)[:, None] == far, 0.0,
                                                             base.speed)))
        return states[0], states[1]

    peak = int(np.argmax(bump))
    passing = check_states(truth, intent, _obs(*with_other_at(xy[peak] - 1.2 * left[peak])))
    assert passing.passed, passing.reason
    alone = check_states(truth, intent, _obs(*with_other_at(xy[peak] + 40.0 * left[peak])))
    assert not alone.passed and "leaves its path" in alone.reason


def test_a_crossing_spot_is_measured_from_the_egos_centre_or_its_front(truth, before) -> None:
    """"8 m in front of us, walking across the road": a person stepping onto the road 8 m past the ego's front
    (12.5 m from its centre) crosses where asked; 25 m ahead does not."""
    ego = truth.road_position(truth.ego_xy[0], float(truth.ego_heading[0]))
    layout = truth.layout
    placement = PlacementIntent("in_front_of", EGO, 8.0)
    for centre_m, ok in ((12.5, True), (25.0, False)):
        spot = layout.arm_point(ego.arm, ego.along - centre_m, 1.0)  # on the road, ahead of the ego
        after = _insert(before, "new_0", "pedestrian", spot, 0.0, (0.6, 0.6, 1.7))
        v = Verdict()
        _check_crossing_spot(truth, placement, after.index("new_0"), after, v)
        assert v.result().passed == ok, (centre_m, v.result().reason)
