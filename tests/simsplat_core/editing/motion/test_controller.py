"""Motion controller on the synthetic intersection (seed 0; world frame = first ego pose, the ego's road runs
along +x) and on the real AV2 map: speeds within limits, stops, turns, lane changes, delays, reversing,
following, pedestrian crossings, refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from simsplat_core.editing.behaviours.gait import RUN_MPS
from simsplat_core.editing.commands import Behaviour, SpeedSpec, StopSpec
from simsplat_core.editing.motion.controller import PlannedTrajectory, plan_pedestrian, plan_vehicle
from simsplat_core.editing.motion.requests import (
    LogTrajectory,
    OtherAgent,
    PedestrianMotionRequest,
    StartState,
    VehicleMotionRequest,
    motion_kind,
)
from simsplat_core.editing.motion.speed_profile import VEHICLE_LIMITS
from simsplat_core.editing.result import EditRefused
from simsplat_core.scenario import metrics as M
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.geometry import footprints_overlap
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.world import WorldConfig, generate_log, layout_from_log

CAR = (4.5, 1.9, 1.5)
PERSON = (0.6, 0.6, 1.8)
DT = 0.1
AV2_LOG = Path("av2") / "sensor-log-7fab2350"


@pytest.fixture(scope="module")
def world():
    log = generate_log(0, WorldConfig(render_images=False))
    return {"log": log, "layout": layout_from_log(log), "ctx": MapContext.from_features(log.map_features),
            "lanes": LaneGraph.from_features(log.map_features), "states": AgentStates.from_log(log)}


def _steps(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.arange(n) * DT, np.arange(n)


def _car(world, behaviour: Behaviour, *, lane: int = 0, before_stop_m: float = 30.0, speed: float = 8.0,
         n: int = 100, **kw) -> PlannedTrajectory:
    """A car inserted on inbound lane ``lane`` of the ego's (west) arm, heading east (+x)."""
    layout = world["layout"]
    xy = layout.arm_point("W", layout.stopline_s("W") + before_stop_m, layout.lane_offset("W", True, lane))
    times, frames = _steps(n)
    req = VehicleMotionRequest.from_behaviour(behaviour, times=times, frame_idx=frames,
                                              start=StartState(0, xy, 0.0, speed), size=CAR, **kw)
    return plan_vehicle(req, world["lanes"], world["ctx"])


def _alone(plan: PlannedTrajectory, category: str = "vehicle", size=CAR) -> AgentStates:
    t = len(plan.times)
    return AgentStates(("x",), (category,), ("inserted",), np.array([-1]), plan.frame_idx, plan.times, plan.xy[None],
                       np.zeros((1, t)), plan.heading[None], plan.speed[None], np.array([size], float),
                       plan.valid[None])


def _accel_jerk(plan: PlannedTrajectory) -> tuple[np.ndarray, np.ndarray]:
    a = np.diff(plan.speed) / np.diff(plan.times)
    return a, np.diff(a) / np.diff(plan.times)[1:]


def _within_limits(plan: PlannedTrajectory, decel: float = VEHICLE_LIMITS.comfort_decel_mps2,
                   jerk: float = VEHICLE_LIMITS.jerk_mps3) -> None:
    a, j = _accel_jerk(plan)
    assert a.max() <= VEHICLE_LIMITS.max_accel_mps2 + 1e-6 and a.min() >= -decel - 1e-6
    assert np.abs(j).max() <= jerk * 1.02  # sampled at 0.1 s
    # positions agree with the speeds (no sliding), and the validation metrics see no infeasible motion
    step = np.linalg.norm(np.diff(plan.xy, axis=0), axis=1) / DT
    np.testing.assert_allclose(step, np.abs(0.5 * (plan.speed[1:] + plan.speed[:-1])), atol=0.05)
    assert not M.kinematic_violations(_alone(plan)).any()


# ------------------------------------------------------------------------------------------ vehicles
def test_requested_speed_is_reached_within_acceleration_and_jerk(world) -> None:
    plan = _car(world, Behaviour(speed=SpeedSpec(value=50, unit="km/h")), speed=5.0, before_stop_m=70.0, n=80)
    assert plan.speed[-1] == pytest.approx(50 / 3.6, abs=0.05)
    _within_limits(plan)
    twice = _car(world, Behaviour(speed=SpeedSpec(mode="factor", value=2.0)), speed=5.0, before_stop_m=70.0, n=60)
    assert twice.speed[-1] == pytest.approx(10.0, abs=0.05)
    slower = _car(world, Behaviour(speed=SpeedSpec(mode="delta", value=-10, unit="km/h")), speed=8.0, n=60)
    assert slower.speed[-1] == pytest.approx(8.0 - 10 / 3.6, abs=0.05)
    _within_limits(slower)
    assert np.all(np.diff(plan.arc_length) >= 0) and plan.valid.all()


def test_stop_before_the_crosswalk_ends_at_rest_in_front_of_it(world) -> None:
    layout = world["layout"]
    plan = _car(world, Behaviour(stop=StopSpec(before="crosswalk")), speed=10.0, before_stop_m=40.0)
    crosswalk_x = layout.arm_point("W", layout.crosswalk_range("W")[1], 0.0)[0]  # its edge facing the car
    front = plan.xy[:, 0] + CAR[0] / 2.0
    assert plan.speed[-1] == 0.0 and front.max() <= crosswalk_x and front[-1] >= crosswalk_x - 3.0
    rest = np.flatnonzero(plan.speed == 0.0)[0]
    assert np.all(plan.speed[rest:] == 0.0) and np.ptp(plan.xy[rest:], axis=0).max() < 1e-9
    _within_limits(plan)
    # a stop that hard braking cannot make is refused, with the distances
    with pytest.raises(EditRefused, match="cannot stop within") as err:
        _car(world, Behaviour(stop=StopSpec(before="crosswalk")), speed=20.0, before_stop_m=8.0)
    assert err.value.reason == "infeasible_motion"


def test_stop_at_a_time_and_hard_braking(world) -> None:
    plan = _car(world, Behaviour(stop=StopSpec(at_time_s=5.0)), speed=10.0, before_stop_m=70.0)
    k5 = int(round(5.0 / DT))
    assert plan.speed[k5] == 0.0 and plan.speed[k5 - 3] > 0.0  # braking as late as comfort allows
    _within_limits(plan)
    hard = _car(world, Behaviour(longitudinal="brake_hard"), speed=10.0, before_stop_m=70.0)
    a, _ = _accel_jerk(hard)
    rest = np.flatnonzero(hard.speed == 0.0)[0]
    assert a.min() < -VEHICLE_LIMITS.comfort_decel_mps2 and a.min() >= -VEHICLE_LIMITS.hard_decel_mps2 - 1e-6
    assert rest * DT < 2.5 and not M.kinematic_violations(_alone(hard)).any()


@pytest.mark.parametrize("turn, lane, sign", [("left", 0, 1.0), ("right", 1, -1.0), ("straight", 0, 0.0)])
def test_turns_follow_the_lanes_through_the_intersection(world, turn: str, lane: int, sign: float) -> None:
    plan = _car(world, Behaviour(turn=turn), lane=lane, speed=8.0, n=120)
    dh = np.rad2deg(plan.heading[-1] - plan.heading[0])
    assert abs(dh - 90.0 * sign) < 8.0
    # on the lanes all the way (within the smoothing of connector joints), on the road, feasible
    d = world["lanes"].nearest(plan.xy).distance
    assert d.max() < 0.3
    report = M.validate_agents(_alone(plan), world["ctx"], [0])
    assert report.ok, report.failures()
    assert plan.speed.min() < 7.0 if turn != "straight" else plan.speed.min() > 7.9  # slows for the curve


def test_a_car_that_halts_short_of_the_intersection_drives_on_to_make_its_turn(world) -> None:
    """Asked to turn, a car whose log brakes to a halt before the intersection drives on to it at its log's pace
    and makes the turn (replaying the log's braking it would never get there)."""
    layout = world["layout"]
    times, frames = _steps(80)
    xy0 = layout.arm_point("W", layout.stopline_s("W") + 30.0, layout.lane_offset("W", True, 1))
    v = np.maximum(8.0 - 2.0 * times, 0.0)  # at rest after 4 s, 16 m on: 14 m short of the stop line
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(times))])
    log = LogTrajectory(xy0 + np.c_[s, 0 * s], np.zeros(80), v, np.ones(80, bool))
    req = VehicleMotionRequest.from_behaviour(Behaviour(turn="right"), times=times, frame_idx=frames,
                                              start=StartState.from_log(log, times), size=CAR, log=log)
    plan = plan_vehicle(req, world["lanes"], world["ctx"])
    assert abs(np.rad2deg(plan.heading[-1] - plan.heading[0]) + 90.0) < 8.0
    assert plan.speed.max() <= v.max() + 0.1 and world["lanes"].nearest(plan.xy).distance.max() < 0.3


def test_turn_refusals_say_what_is_missing(world) -> None:
    # the inner lane has no right-turn connector in this world, and 0.5 s is not enough to reach a turn
    with pytest.raises(EditRefused, match="turning requires an intersection ahead of the target") as err:
        _car(world, Behaviour(turn="right"), lane=0)
    assert err.value.reason == "infeasible_motion"
    with pytest.raises(EditRefused, match="within reach") as err:
        _car(world, Behaviour(turn="left"), lane=0, before_stop_m=60.0, n=20)
    assert err.value.reason == "infeasible_motion"
    off_map = VehicleMotionRequest.from_behaviour(Behaviour(turn="left"), times=_steps(20)[0], frame_idx=_steps(20)[1],
                                                  start=StartState(0, np.array([500.0, 500.0]), 0.0, 5.0), size=CAR)
    with pytest.raises(EditRefused, match="not on a lane"):
        plan_vehicle(off_map, world["lanes"], world["ctx"])


def test_lane_change_ends_one_lane_to_the_side(world) -> None:
    layout = world["layout"]
    width = layout.lane_w("W")
    plan = _car(world, Behaviour(lane_change="right"), lane=0, speed=8.0, before_stop_m=70.0, n=70)
    y0 = plan.xy[0, 1]
    assert plan.xy[-1, 1] - y0 == pytest.approx(-width, abs=0.05)  # heading +x: right is -y
    lateral = plan.xy[:, 1] - y0
    assert np.all(np.diff(lateral) <= 1e-9)  # monotone, no overshoot
    moving = np.flatnonzero(np.abs(lateral + width) > 0.01)
    assert 2.5 < moving[-1] * DT < 5.0  # about 3.5 s
    lat_acc = np.abs(np.diff(lateral, 2)) / DT ** 2
    assert lat_acc.max() < 2.0 and not M.kinematic_violations(_alone(plan)).any()
    with pytest.raises(EditRefused, match="no lane to the left of the target") as err:
        _car(world, Behaviour(lane_change="left"), lane=0)
    assert err.value.reason == "infeasible_motion"


def test_delayed_start_holds_still_until_the_delay(world) -> None:
    plan = _car(world, Behaviour(delay_s=2.0), speed=8.0, before_stop_m=70.0)
    held = plan.times < 2.0 - 1e-9
    assert np.all(plan.speed[held] == 0.0) and np.ptp(plan.xy[held], axis=0).max() < 1e-9
    assert plan.speed[int(2.0 / DT) + 5] > 0.5 and plan.speed[-1] == pytest.approx(8.0, abs=0.05)
    _within_limits(plan)
    later = _car(world, Behaviour(start_time_s=3.0), speed=8.0, before_stop_m=70.0)
    assert np.all(later.speed[later.times < 3.0 - 1e-9] == 0.0) and later.speed[-1] > 7.9


def test_reverse_moves_backwards(world) -> None:
    plan = _car(world, Behaviour(reverse=True), speed=4.0, n=80)  # brakes from 4 m/s, then backs up
    forward = np.array([1.0, 0.0])
    assert plan.speed[-1] == pytest.approx(-2.0, abs=0.05)
    assert np.dot(plan.xy[-1] - plan.xy[0], forward) < -5.0
    assert np.abs(plan.heading - plan.heading[0]).max() < 1e-6  # still facing forward
    _within_limits(plan)


def test_follower_keeps_a_gap_to_its_leader(world) -> None:
    layout = world["layout"]
    times, frames = _steps(100)
    lead_xy0 = layout.arm_point("W", layout.stopline_s("W") + 45.0, layout.lane_offset("W", True, 0))
    lead = OtherAgent("lead", "the red car", lead_xy0 + np.c_[5.0 * times, 0 * times], np.zeros(100),
                      np.ones(100, bool), CAR)
    plan = _car(world, Behaviour(speed=SpeedSpec(value=12.0), follow={"description": "the red car"}),
                before_stop_m=75.0, speed=10.0, leader=lead)
    gap = lead.xy[:, 0] - plan.xy[:, 0] - CAR[0]  # bumper to bumper
    assert gap.min() >= 2.0 and abs(plan.speed[-1] - 5.0) < 0.5
    not_following = _car(world, Behaviour(speed=SpeedSpec(value=12.0)), before_stop_m=75.0, speed=10.0)
    assert (lead.xy[:, 0] - not_following.xy[:, 0] - CAR[0]).min() < 0.0  # without following it would hit it
    with pytest.raises(EditRefused, match="cannot follow the red car: it is not ahead"):
        behind = OtherAgent("lead", "the red car", lead.xy - [80.0, 0.0], lead.heading, lead.valid, CAR)
        _car(world, Behaviour(follow={"description": "the red car"}), before_stop_m=75.0, leader=behind)


def test_traffic_in_the_way_is_given_room(world) -> None:
    layout = world["layout"]
    times, frames = _steps(80)
    start = layout.arm_point("W", layout.stopline_s("W") + 75.0, layout.lane_offset("W", True, 0))
    slow = OtherAgent("slow", "a slow car", start + [25.0, 0.0] + np.c_[3.0 * times, 0 * times], np.zeros(80),
                      np.ones(80, bool), CAR)
    # a person crossing the lane 40 m ahead, stepping onto it at 2.5 s
    walk_y = start[1] - 6.0 + 1.4 * np.clip(times - 0.5, 0.0, None)
    person = OtherAgent("ped", "a person", np.c_[np.full(80, start[0] + 40.0), walk_y], np.full(80, np.pi / 2),
                        np.ones(80, bool), PERSON)
    for other in (slow, person):
        plan = _car(world, Behaviour(), before_stop_m=75.0, speed=10.0, n=80, traffic=(other,))
        blind = _car(world, Behaviour(), before_stop_m=75.0, speed=10.0, n=80)
        for traj, hits in ((plan, False), (blind, True)):
            overlap = footprints_overlap(traj.xy, traj.heading, CAR[:2], other.xy, other.heading, other.size[:2])
            assert overlap.any() == hits, other.label
        # braking for what is in the way may use the hard limits
        _within_limits(plan, decel=VEHICLE_LIMITS.hard_decel_mps2, jerk=VEHICLE_LIMITS.hard_jerk_mps3)


def test_traffic_entering_behind_a_car_does_not_hold_it_back(world) -> None:
    """A car turning in from a side road enters the lane just ahead of where a speeding-up car is now, but only
    after that car has passed the spot: the car speeds up instead of braking for it, and never touches it."""
    layout = world["layout"]
    times, _ = _steps(40)
    start = layout.arm_point("W", layout.stopline_s("W") + 75.0, layout.lane_offset("W", True, 0))
    entry, arrive, side_v = start + [CAR[0], 0.0], 2.0, 6.0  # reaches the lane's centre line at 2 s
    before = times < arrive
    xy = np.where(before[:, None], entry + np.c_[0 * times, -side_v * (arrive - times)],
                  entry + np.c_[5.0 * (times - arrive), 0 * times])
    turner = OtherAgent("turner", "a turning car", xy, np.where(before, np.pi / 2, 0.0), np.ones(40, bool), CAR)
    plan = _car(world, Behaviour(longitudinal="accelerate"), before_stop_m=75.0, speed=8.0, n=40, traffic=(turner,))
    free = _car(world, Behaviour(longitudinal="accelerate"), before_stop_m=75.0, speed=8.0, n=40)
    np.testing.assert_allclose(plan.speed, free.speed, atol=1e-6)  # as if the road were free
    assert plan.speed[-1] > plan.speed[0]
    assert not footprints_overlap(plan.xy, plan.heading, CAR[:2], turner.xy, turner.heading, CAR[:2]).any()
    assert not footprints_overlap(plan.xy, plan.heading, CAR[:2], turner.xy, turner.heading, CAR[:2]).any()


def test_a_person_on_the_corner_pavement_beside_a_right_turn_does_not_stop_it(world) -> None:
    """The turn's path passes within a couple of metres of the kerb: a person standing on the pavement there
    is no obstacle; the same person standing on the road in the path is."""
    free = _car(world, Behaviour(turn="right"), lane=1, speed=8.0, n=60)
    turning = np.flatnonzero(np.abs(np.diff(free.heading)) > 1e-3)
    right = np.c_[np.sin(free.heading), -np.cos(free.heading)]
    # the first point of the pavement within 2.4 m to the right of the turn's path
    k, inside = next((int(k), free.xy[k] + off * right[k]) for k in turning for off in np.arange(1.0, 2.45, 0.1)
                     if not world["ctx"].facts((free.xy[k] + off * right[k])[None], np.zeros(1)).on_drivable[0])

    def standing_at(xy: np.ndarray) -> OtherAgent:
        return OtherAgent("ped", "a person", np.tile(xy, (60, 1)), np.zeros(60), np.ones(60, bool), PERSON)

    on_pavement = _car(world, Behaviour(turn="right"), lane=1, speed=8.0, n=60, traffic=(standing_at(inside),))
    np.testing.assert_allclose(on_pavement.xy, free.xy, atol=1e-6)
    with pytest.raises(EditRefused, match="turning requires"):  # stands in the path all along: no turn
        _car(world, Behaviour(turn="right"), lane=1, speed=8.0, n=60, traffic=(standing_at(free.xy[k]),))


def test_a_person_standing_beside_the_lane_does_not_stop_a_car_but_one_in_it_does(world) -> None:
    """A person standing on the road 2.3 m off the car's lane centre (the edge of a crosswalk) leaves a car room
    to pass; 0.5 m off it, the car stops short of them."""
    layout = world["layout"]
    start = layout.arm_point("W", layout.stopline_s("W") + 75.0, layout.lane_offset("W", True, 0))

    def person_at(lateral: float) -> OtherAgent:
        xy = start + np.array([30.0, lateral])  # the arm runs along +x from the ego's start
        assert world["ctx"].facts(xy[None], np.zeros(1)).on_drivable[0]
        return OtherAgent("ped", "a person", np.tile(xy, (80, 1)), np.zeros(80), np.ones(80, bool), PERSON)

    free = _car(world, Behaviour(), before_stop_m=75.0, speed=10.0, n=80)
    beside = _car(world, Behaviour(), before_stop_m=75.0, speed=10.0, n=80, traffic=(person_at(2.3),))
    np.testing.assert_allclose(beside.xy, free.xy, atol=1e-6)
    ahead = person_at(0.5)
    held = _car(world, Behaviour(), before_stop_m=75.0, speed=10.0, n=80, traffic=(ahead,))
    assert not footprints_overlap(held.xy, held.heading, CAR[:2], ahead.xy, ahead.heading, PERSON[:2]).any()
    assert held.speed[-1] < 0.5  # nearly at rest short of them


def test_a_slowed_car_keeps_the_gap_its_log_kept(world) -> None:
    """A car that in its log follows the car ahead closely (much closer than the planner's own headway) and is
    asked to go slower only drops back: it slows to the asked speed without braking below it, and stays at least
    as far behind as its log did; placed there without a log it brakes to open the gap it wants."""
    layout = world["layout"]
    times, frames = _steps(40)
    xy0 = layout.arm_point("W", layout.stopline_s("W") + 75.0, layout.lane_offset("W", True, 0))
    v_log = 10.0
    log = LogTrajectory(xy0 + np.c_[v_log * times, 0 * times], np.zeros(40), np.full(40, v_log), np.ones(40, bool))
    lead = OtherAgent("lead", "the car ahead", log.xy + [CAR[0] + 2.5, 0.0], np.zeros(40), np.ones(40, bool), CAR)
    slower = Behaviour(speed=SpeedSpec(mode="delta", value=-3.0, unit="m/s"))

    def plan(with_log: bool) -> tuple[VehicleMotionRequest, PlannedTrajectory]:
        req = VehicleMotionRequest.from_behaviour(slower, times=times, frame_idx=frames,
                                                  start=StartState.from_log(log, times), size=CAR,
                                                  log=log if with_log else None, traffic=(lead,))
        return req, plan_vehicle(req, world["lanes"], world["ctx"])

    req, edited = plan(True)
    assert req.target_speed_mps is not None
    assert edited.speed[-1] == pytest.approx(req.target_speed_mps, abs=0.05)
    assert edited.speed.min() >= req.target_speed_mps - 0.05
    assert np.all(lead.xy[:, 0] - edited.xy[:, 0] >= lead.xy[:, 0] - log.xy[:, 0] - 1e-6)
    _within_limits(edited)
    _, inserted = plan(False)
    assert inserted.speed.min() < req.target_speed_mps - 0.5


def test_modify_keeps_the_log_where_the_behaviour_does_not_change_it(world) -> None:
    st = world["states"]
    row = next(r for r in range(1, st.num_agents) if st.categories[r] == "vehicle"  # driving straight on
               and np.abs(st.speed[r]).min() > 3.0 and st.valid[r].all() and np.ptp(st.heading[r]) < 0.05)
    log = LogTrajectory.from_states(st, row)
    start = StartState.from_log(log, st.times, step=10)
    shift = VehicleMotionRequest.from_behaviour(Behaviour(lateral_offset_m=1.0), times=st.times,
                                                frame_idx=st.frame_idx, start=start, size=tuple(st.size[row]),
                                                log=log)
    plan = plan_vehicle(shift, world["lanes"], world["ctx"])
    np.testing.assert_array_equal(plan.xy[:10], log.xy[:10])  # before the command's frame: the log
    np.testing.assert_allclose(plan.speed[10:-1], np.abs(log.speed[10:-1]), atol=0.05)  # the log's own progress
    left = np.array([-np.sin(log.heading[-1]), np.cos(log.heading[-1])])
    assert np.dot(plan.xy[-1] - log.xy[-1], left) == pytest.approx(1.0, abs=0.1)
    faster = VehicleMotionRequest.from_behaviour(Behaviour(speed=SpeedSpec(mode="factor", value=1.5)),
                                                 times=st.times, frame_idx=st.frame_idx,
                                                 start=StartState.from_log(log, st.times), size=tuple(st.size[row]),
                                                 log=log)
    fast = plan_vehicle(faster, world["lanes"], world["ctx"])
    assert fast.speed[-1] == pytest.approx(1.5 * abs(log.speed[0]), abs=0.05)
    assert fast.arc_length[-1] > 1.2 * np.linalg.norm(np.diff(log.xy, axis=0), axis=1).sum()


def test_pose_track_carries_the_plan(world) -> None:
    plan = _car(world, Behaviour(turn="left"), n=120)
    track = plan.pose_track(0.75)
    poses, present = track.sample_many(plan.frame_idx.astype(float))
    np.testing.assert_allclose(poses[:, :2, 3].numpy(), plan.xy, atol=1e-4)
    np.testing.assert_allclose(poses[:, 2, 3].numpy(), 0.75)
    yaw = np.arctan2(poses[:, 1, 0].numpy(), poses[:, 0, 0].numpy())
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - plan.heading))), 0.0, atol=1e-5)
    assert present.numpy().all()


# ------------------------------------------------------------------------------------------ pedestrians
def _person(world, behaviour: Behaviour, xy: np.ndarray, heading: float, speed: float = 0.0,
            n: int = 150) -> PlannedTrajectory:
    times, frames = _steps(n)
    req = PedestrianMotionRequest.from_behaviour(behaviour, times=times, frame_idx=frames,
                                                 start=StartState(0, np.asarray(xy, float), heading, speed),
                                                 size=PERSON)
    return plan_pedestrian(req, world["ctx"])


def test_pedestrian_crosses_at_the_crosswalk_or_jaywalks_away_from_it(world) -> None:
    layout, ctx = world["layout"], world["ctx"]
    kerb = layout.hw_h + 1.5  # on the sidewalk left of the ego's road (local +v side of the W arm is -y)
    near_cw = layout.arm_point("W", layout.crosswalk_range("W")[1] + 6.0, -kerb)
    plan = _person(world, Behaviour(cross_street=True), near_cw, 0.0, n=250)
    facts = ctx.facts(plan.xy, plan.heading)
    assert facts.in_crosswalk.sum() > 10 and facts.on_drivable.any()
    assert not facts.on_drivable[-1] and facts.on_sidewalk[-1]  # on the far sidewalk
    assert np.sign(plan.xy[-1, 1] - layout.center[1]) != np.sign(near_cw[1] - layout.center[1])
    assert plan.speed.max() == pytest.approx(1.4, abs=0.02)
    jay = _person(world, Behaviour(jaywalk=True), near_cw, 0.0, n=250)
    jfacts = ctx.facts(jay.xy, jay.heading)
    assert not jfacts.in_crosswalk.any() and jfacts.on_drivable.any() and jfacts.on_sidewalk[-1]
    assert np.sign(jay.xy[-1, 1] - layout.center[1]) != np.sign(near_cw[1] - layout.center[1])
    # a person in the middle of a block crosses straight over, perpendicular to the road
    mid = layout.arm_point("W", 50.0, -kerb)
    straight = _person(world, Behaviour(jaywalk=True), mid, 0.0, n=250)
    assert abs(straight.xy[-1, 0] - mid[0]) < 0.5


def test_a_crosswalk_out_of_reach_within_the_log_is_not_walked_to(world) -> None:
    """Told to cross with 4 s left, a person 30 m from the nearest crosswalk crosses where it stands (it would
    spend the whole log walking along the kerb); with a minute left it walks to the crosswalk."""
    layout, ctx = world["layout"], world["ctx"]
    kerb = layout.hw_h + 1.5
    spot = layout.arm_point("W", layout.crosswalk_range("W")[1] + 30.0, -kerb)
    short = _person(world, Behaviour(cross_street=True), spot, 0.0, n=40)
    facts = ctx.facts(short.xy, short.heading)
    assert facts.on_drivable.any() and not facts.in_crosswalk.any()
    assert np.abs(short.xy[:, 0] - spot[0]).max() < 0.5  # straight across
    long = _person(world, Behaviour(cross_street=True), spot, 0.0, n=600)
    assert ctx.facts(long.xy, long.heading).in_crosswalk.sum() > 10


def test_pedestrian_gaits_and_stops(world) -> None:
    layout = world["layout"]
    spot = layout.arm_point("W", 50.0, -(layout.hw_h + 1.5))
    run = _person(world, Behaviour(gait="run"), spot, np.pi, speed=1.4, n=60)
    assert run.speed[-1] == pytest.approx(RUN_MPS, abs=0.02)
    a = np.diff(run.speed) / DT
    assert a.max() <= 1.5 + 1e-6
    stop = _person(world, Behaviour(stop=StopSpec(at_time_s=2.0)), spot, np.pi, speed=1.4, n=40)
    assert np.all(stop.speed[stop.times >= 2.0] == 0.0)
    assert not M.kinematic_violations(_alone(stop, "pedestrian", PERSON)).any()


def test_behaviours_of_the_wrong_category_are_refused(world) -> None:
    times, frames = _steps(10)
    start = StartState(0, np.zeros(2), 0.0, 1.0)
    for behaviour, reason, words in ((Behaviour(lane_change="left"), "wrong_category", "lane change is for vehicles"),
                                     (Behaviour(turn="left"), "wrong_category", "turn is for vehicles"),
                                     (Behaviour(reverse=True), "infeasible_motion", "pedestrians do not reverse")):
        with pytest.raises(EditRefused, match=words) as err:
            PedestrianMotionRequest.from_behaviour(behaviour, times=times, frame_idx=frames, start=start, size=PERSON)
        assert err.value.reason == reason
    with pytest.raises(EditRefused, match="jaywalk is for pedestrians") as err:
        VehicleMotionRequest.from_behaviour(Behaviour(jaywalk=True), times=times, frame_idx=frames, start=start,
                                            size=CAR)
    assert err.value.reason == "wrong_category"
    with pytest.raises(EditRefused, match="static objects cannot move") as err:
        motion_kind("static", "the cone")
    assert err.value.reason == "wrong_category" and motion_kind("cyclist") == "vehicle"


# ------------------------------------------------------------------------------------------ AV2
@pytest.mark.shared_data
def test_av2_turns_and_stops_on_the_real_map(shared_data: Path) -> None:
    from simsplat_core.data import load_av2_log

    log_dir = shared_data / AV2_LOG
    if not log_dir.exists():
        pytest.skip("AV2 sample absent")
    log = load_av2_log(log_dir)
    st = AgentStates.from_log(log)
    ctx, lanes = MapContext.from_features(log.map_features), LaneGraph.from_features(log.map_features)
    movers = [r for r in range(1, st.num_agents) if st.categories[r] == "vehicle"
              and np.abs(st.speed[r]).max() > 5.0 and st.valid[r].sum() > 100]
    turned = stopped = refused = 0
    for row in movers:
        lg = LogTrajectory.from_states(st, row)
        start = StartState.from_log(lg, st.times)
        for behaviour in (Behaviour(turn="left"), Behaviour(stop=StopSpec(before="crosswalk"))):
            req = VehicleMotionRequest.from_behaviour(behaviour, times=st.times, frame_idx=st.frame_idx,
                                                      start=start, size=tuple(st.size[row]), log=lg)
            try:
                plan = plan_vehicle(req, lanes, ctx)
            except EditRefused as err:
                assert err.reason == "infeasible_motion" and str(err)
                refused += 1
                continue
            edited = st.with_agent(st.object_ids[row], "vehicle", "edited", xy=plan.xy, heading=plan.heading,
                                   speed=plan.speed, valid=plan.valid, size=st.size[row])
            entry = M.validate_agents(edited, ctx, [row]).agent(st.object_ids[row])
            assert not entry.kinematic and not entry.offroad, entry
            if behaviour.turn:
                s_turn = plan.route.marks["turn"]
                dh = np.rad2deg(plan.route.heading(plan.route.marks["turn_end"]) - plan.route.heading(s_turn))
                assert dh > 60.0
                turned += 1
            else:
                s_cw = [plan.route.project(p)[0] for p in plan.xy[-1:]][0] + st.size[row, 0] / 2.0
                assert plan.speed[-1] == 0.0
                assert not ctx.facts(plan.route.position(np.array([s_cw])), plan.heading[-1:]).in_crosswalk[0]
                stopped += 1
    # measured: 5 left turns, 9 stops before a crosswalk, 18 refused (no left turn / crosswalk within reach) of 32
    assert turned >= 2 and stopped >= 2 and refused >= 2


@pytest.mark.parametrize(("gap_m", "holds"), [(25.0, True), (40.0, True), (6.0, False)])
def test_a_plan_at_its_wanted_speed_holds_it_behind_a_leader_leaving_it_room(gap_m: float, holds: bool) -> None:
    """The gap keeping is the Improved IDM: at the wanted speed with more than the wanted gap (1.5 s headway) to a
    leader driving as fast, the plan holds its speed (the plain IDM braked below it even with 40 m of room);
    closer than the headway it still drops back."""
    from simsplat_core.editing.motion.speed_profile import LeaderTrack, plan_speed

    times = np.arange(40) * 0.1
    v = 8.0
    lead_s = gap_m + 6.5 + v * times  # net gap gap_m at the start (gap_m below covers both half lengths + 2 m)
    leader = LeaderTrack(s=lead_s[None], v=np.full((1, 40), v), present=np.ones((1, 40), bool),
                         gap_m=np.array([6.5]))
    plan = plan_speed(times, t0=0.0, s0=0.0, v0=v, v_ref=lambda t: v, limits=VEHICLE_LIMITS, leader=leader)
    assert (float(np.abs(plan.v).min()) >= v - 0.05) is holds, plan.v.round(2)


@pytest.mark.parametrize(("speed", "by_s"), [(9.8, 2.5), (12.0, 2.5), (8.0, 1.8)])
def test_a_stop_by_a_time_too_soon_for_comfort_brakes_harder_and_stands_by_then(world, speed: float,
                                                                              by_s: float) -> None:
    """Comfortable braking (3 m/s^2, jerk 5) from ~10 m/s takes ~3.5 s; a stop asked by 2.5 s brakes harder
    (within the hard limits) and stands by then (it stood only from ~3.6 s before)."""
    plan = _car(world, Behaviour(stop=StopSpec(at_time_s=by_s)), speed=speed, before_stop_m=70.0, n=60)
    still = np.flatnonzero(np.abs(plan.speed) < 0.05)
    assert still.size and plan.times[still[0]] <= by_s + 0.15, plan.speed.round(2)
    _within_limits(plan, decel=VEHICLE_LIMITS.hard_decel_mps2, jerk=VEHICLE_LIMITS.hard_jerk_mps3)


def test_a_stop_by_a_time_even_hard_braking_cannot_make_is_refused(world) -> None:
    with pytest.raises(EditRefused, match=r"cannot be at rest by 0.5 s: braking as hard as allowed") as err:
        _car(world, Behaviour(stop=StopSpec(at_time_s=0.5)), speed=14.0, before_stop_m=70.0, n=60)
    assert err.value.reason == "infeasible_motion"


@pytest.mark.parametrize("before_stop_m", [6.0, 12.0])
def test_a_car_whose_log_turns_left_goes_straight_when_asked(world, before_stop_m: float) -> None:
    """Asked to go straight, a car whose log turns left at the intersection drives straight through it: the
    lane under a point of its path already in the turn is a turning lane, not a straight candidate."""
    layout = world["layout"]
    n = 80
    times, frames = _steps(n)
    xy0 = layout.arm_point("W", layout.stopline_s("W") + before_stop_m, layout.lane_offset("W", True, 0))
    lp = world["lanes"].follow(xy0, 0.0, "left")
    s = lp.start_s + 7.0 * times
    log = LogTrajectory(lp.path.position(s), lp.path.heading(s), np.full(n, 7.0), np.ones(n, bool))
    assert np.rad2deg(log.heading[-1] - log.heading[0]) > 60.0  # the log turns left
    req = VehicleMotionRequest.from_behaviour(Behaviour(turn="straight"), times=times, frame_idx=frames,
                                              start=StartState.from_log(log, times), size=CAR, log=log)
    plan = plan_vehicle(req, world["lanes"], world["ctx"])
    assert abs(np.rad2deg(plan.heading[-1] - plan.heading[0])) < 10.0
    assert world["lanes"].nearest(plan.xy).distance.max() < 0.3


@pytest.mark.parametrize("into_turn_deg", [5.0, 15.0])
def test_a_car_just_into_its_turn_can_still_go_straight_on(world, into_turn_deg: float) -> None:
    """A car whose log turns right at the junction, asked to go straight on once it has turned a few degrees (on
    the approach lane, or already on the turning connector), leaves its turn and drives straight through the
    junction; well into the turn it can only keep turning."""
    log_plan = _car(world, Behaviour(turn="right"), lane=1, speed=8.0, n=120)
    times, frames = log_plan.times, log_plan.frame_idx
    log = LogTrajectory(log_plan.xy, log_plan.heading, log_plan.speed, log_plan.valid)

    def straight_from(deg: float) -> PlannedTrajectory:
        k = int(np.flatnonzero(np.abs(np.rad2deg(log_plan.heading)) >= deg)[0])
        start = StartState(k, log_plan.xy[k], float(log_plan.heading[k]), float(log_plan.speed[k]))
        req = VehicleMotionRequest.from_behaviour(Behaviour(turn="straight"), times=times, frame_idx=frames,
                                                  start=start, size=CAR, log=log)
        return plan_vehicle(req, world["lanes"], world["ctx"])

    plan = straight_from(into_turn_deg)
    assert abs(np.rad2deg(log_plan.heading[-1]) + 90.0) < 8.0  # the log goes south
    assert abs(np.rad2deg(plan.heading[-1])) < 5.0  # east, the way it came
    assert plan.xy[-1, 0] > log_plan.xy[-1, 0] + 10.0
    assert world["lanes"].nearest(plan.xy[-20:]).distance.max() < 0.3
    assert abs(np.rad2deg(straight_from(45.0).heading[-1]) + 90.0) < 8.0
