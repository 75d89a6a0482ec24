"""ReactivePredictor on hand-built scenes: a straight two-lane road (lane 0 at y = 0, lane 1 at y = 3.5, both
eastbound), 11 history steps and 80 future steps at 10 Hz."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.corridor import box_extents, nearest_ahead, route_pairs
from simsplat_core.motion.predictor import MotionMap, MotionPredictor, RolloutRequest
from simsplat_core.motion.reactive import ReactivePredictor
from simsplat_core.motion.route_grid import RouteGrid
from simsplat_core.motion.routes import APPEARS_LATER, NO_LANE, STATIC_OBJECT, STATIONARY, project_points
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.metrics import collision_steps, kinematic_violations
from simsplat_core.scenario.path import Path
from tests.simsplat_core.motion.scenes import CAR, DT, PERSON, START, TIMES, TRUCK, T, road, states, track


def rollout(st: AgentStates, fixed: list[str], mp: MotionMap | None = None, **kw: object):
    req = RolloutRequest(st, START, np.array([st.index(o) for o in fixed], dtype=np.int64), mp or road(), **kw)
    return ReactivePredictor().rollout(req)


def collides(st: AgentStates, row: int) -> bool:
    return bool(collision_steps(st, [row], count_log_pairs=True).pairs.any())


def feasible(st: AgentStates, row: int) -> bool:
    """No Waymax-style kinematic bound (acceleration, jerk, curvature, ...) exceeded over the future."""
    return not kinematic_violations(st, rows=[row])[:, START:].any()


# ------------------------------------------------------------------------------------------ (a) free road
def test_protocol_and_free_road_reproduces_the_log() -> None:
    assert isinstance(ReactivePredictor(), MotionPredictor)
    accel = np.clip(TIMES - 2.0, 0.0, 3.0)  # speeds up from 8 to 11 m/s
    x_a = 8.0 * TIMES + 0.5 * np.cumsum(accel) * DT
    x_b = 20.0 + 12.0 * TIMES - 0.3 * np.clip(TIMES - 4.0, 0.0, None) ** 2  # slows down
    st = states([("ego", "vehicle", track(-60.0 + 10.0 * TIMES, 3.5), CAR),
                 ("a", "vehicle", track(x_a, 0.0), CAR),
                 ("b", "vehicle", track(x_b + 40.0, 3.5), CAR),
                 ("p", "pedestrian", track(10.0 + 1.3 * TIMES, -4.0), PERSON)])
    out = rollout(st, ["ego"])
    assert out.predictor == "reactive" and out.replayed == {}
    err = np.linalg.norm(out.states.xy[:, START:] - st.xy[:, START:], axis=-1)
    assert err.mean() < 0.1 and err.max() < 0.3
    head_err = np.abs(np.angle(np.exp(1j * (out.states.heading[:, START:] - st.heading[:, START:]))))
    assert head_err.max() < 0.05
    assert out.states.sources == ("log",) * 4
    assert out.states.valid.all()


def test_a_logged_right_turn_stays_a_right_turn() -> None:
    """Off the lane graph (a turn at a junction the map does not cover), the logged arc is followed."""
    radius, v = 15.0, 7.0
    ang = np.clip(v * (TIMES - 2.0) / radius, 0.0, np.pi / 2)
    straight = np.clip(v * TIMES, None, 2.0 * v)
    x = np.where(TIMES < 2.0, straight, 2.0 * v + radius * np.sin(ang)) - 10.0
    y = np.where(TIMES < 2.0, 0.0, -radius * (1.0 - np.cos(ang)))
    tail = np.clip(v * (TIMES - 2.0) - radius * np.pi / 2, 0.0, None)  # southbound after the quarter circle
    y = y - tail
    st = states([("ego", "vehicle", track(-40.0 + 5.0 * TIMES, 3.5), CAR), ("turner", "vehicle", track(x, y), CAR)])
    out = rollout(st, ["ego"])
    err = np.linalg.norm(out.states.xy[1, START:] - st.xy[1, START:], axis=-1)
    assert err.max() < 0.5
    assert abs(np.angle(np.exp(1j * (out.states.heading[1, -1] + np.pi / 2)))) < 0.1  # heading south at the end


# ------------------------------------------------------------------------------------------ (b) braking leader
def test_follower_brakes_behind_a_leader_that_stops_hard() -> None:
    v_lead = np.clip(12.0 - 8.0 * np.clip(TIMES - 3.0, 0.0, None), 0.0, None)
    x_lead = 20.0 + np.concatenate([[0.0], np.cumsum(0.5 * (v_lead[1:] + v_lead[:-1]) * DT)])
    st = states([("lead", "vehicle", track(x_lead, 0.0), CAR), ("f", "vehicle", track(12.0 * TIMES, 0.0), CAR)])
    assert collides(st, 1)  # replaying the log, the follower drives into the leader
    out = rollout(st, ["lead"])
    assert not collides(out.states, 1) and feasible(out.states, 1)
    assert out.states.speed[1, -1] < 0.5 and out.states.sources[1] == "refined"
    gap = out.states.xy[0, START:, 0] - out.states.xy[1, START:, 0] - CAR[0]
    assert gap.min() > 1.5 and gap[-1] < 3.0  # closing in on IDM's standstill gap (2 m)


# ------------------------------------------------------------------------------------------ (c) crossing
def test_car_yields_to_a_fixed_agent_crossing_its_path() -> None:
    crosser = track(np.full(T, 50.0), -30.0 + 8.0 * TIMES)  # northbound, at y = 0 at t = 3.75 s
    crosser["heading"][:] = np.pi / 2
    st = states([("x", "vehicle", crosser, CAR), ("car", "vehicle", track(12.5 + 10.0 * TIMES, 0.0), CAR)])
    assert collides(st, 1)
    out = rollout(st, ["x"])
    assert not collides(out.states, 1) and feasible(out.states, 1)
    car_x = out.states.xy[1, :, 0]
    assert car_x[int(3.75 / DT)] < 50.0 - 2.25 - 1.0  # held back while the crosser passes
    assert car_x[-1] > 60.0  # and went on afterwards
    assert out.states.speed[1, START:].min() < 7.0  # slowed down to let it pass


# ------------------------------------------------------------------------------------------ (d) pedestrian
def test_pedestrian_waits_for_a_vehicle_about_to_pass_its_crosswalk() -> None:
    walker = track(np.full(T, 30.0), -4.2 + 1.4 * TIMES)  # in the lane when the car passes (t = 3 s)
    walker["heading"][:] = np.pi / 2
    st = states([("car", "vehicle", track(10.0 * TIMES, 0.0), CAR), ("p", "pedestrian", walker, PERSON)])
    assert collides(st, 1)
    out = rollout(st, ["car"], road(with_crosswalk=True))
    assert not collides(out.states, 1) and feasible(out.states, 1)
    y = out.states.xy[1, :, 1]
    assert y[int(3.0 / DT)] < -1.0 - 0.3  # waiting short of the car's side
    assert y[-1] > 3.0  # crossed after the car had passed


def test_car_gives_way_to_an_inserted_pedestrian_that_steps_out_later() -> None:
    """The pedestrian exists only from t = 3.3 s, 5 m ahead of the car (an edit: "a pedestrian steps out"): too
    late to stop within the kinematic limits then, so the car must see it coming from its given future."""
    walker = track(np.full(T, 40.0), -2.0 + 1.8 * np.clip(TIMES - 3.3, 0.0, None))
    walker["heading"][:] = np.pi / 2
    st = states([("car", "vehicle", track(10.0 * TIMES, 0.0), CAR), ("p", "pedestrian", walker, PERSON)],
                valid={"p": TIMES >= 3.3})
    assert collides(st, 0)
    out = rollout(st, ["p"], road(with_crosswalk=True))
    assert not collides(out.states, 0) and feasible(out.states, 0)
    assert out.states.xy[0, -1, 0] > 45.0  # and drove on once the pedestrian had crossed


# ------------------------------------------------------------------------------------------ (e) stopped obstacle
@pytest.mark.parametrize("left_lane_busy", [False, True])
def test_follower_detours_around_or_stops_behind_a_stopped_truck(left_lane_busy: bool) -> None:
    agents = [("truck", "vehicle", track(np.full(T, 80.0), 0.0), TRUCK),
              ("f", "vehicle", track(10.0 * TIMES, 0.0), CAR)]
    if left_lane_busy:  # a platoon in the left lane, 15 m apart at 10 m/s, passing the truck all the time
        agents += [(f"side{k}", "vehicle", track(x0 + 10.0 * TIMES, 3.5), CAR)
                   for k, x0 in enumerate(np.arange(-60.0, 100.0, 15.0))]
    st = states(agents)
    assert collides(st, 1)
    fixed = [o for o in st.object_ids if o != "f"]
    out = rollout(st, fixed)
    assert not collides(out.states, 1) and feasible(out.states, 1)
    end_y = out.states.xy[1, -1, 1]
    if left_lane_busy:
        assert abs(end_y) < 0.5 and out.states.xy[1, -1, 0] < 80.0 - 4.0 - 2.25
    else:
        assert abs(end_y - 3.5) < 0.3 and out.states.xy[1, -1, 0] > 80.0 + 4.0 + 2.25  # in the left lane, past it
        dyaw = np.abs(np.diff(out.states.heading[1, START - 1:]))
        assert dyaw.max() < 0.05  # a smooth move (rad per step)


# ------------------------------------------------------------------------------------------ (f) replayed
def test_agents_without_a_route_are_replayed_with_a_reason() -> None:
    lost = track(np.full(T, 0.0) + 5.0 * TIMES, 50.0)  # far from every lane, log ends at the last observed step
    late = track(30.0 + 10.0 * TIMES, 0.0)
    valid_lost = np.arange(T) < START
    valid_late = np.arange(T) >= 30
    st = states([("ego", "vehicle", track(10.0 * TIMES, 3.5), CAR), ("lost", "vehicle", lost, CAR),
                 ("late", "vehicle", late, CAR), ("parked", "vehicle", track(np.full(T, 60.0), -3.0), CAR),
                 ("cone", "static", track(np.full(T, 70.0), -2.5), (0.4, 0.4, 0.7))],
                valid={"lost": valid_lost, "late": valid_late})
    out = rollout(st, ["ego"])
    assert out.replayed == {"lost": NO_LANE, "late": APPEARS_LATER, "parked": STATIONARY, "cone": STATIC_OBJECT}
    for name in ("xy", "heading", "speed", "valid"):
        np.testing.assert_array_equal(getattr(out.states, name)[1:], getattr(st, name)[1:])


# ------------------------------------------------------------------------------------------ (g) fixed rows
def test_fixed_rows_and_history_unchanged_and_deterministic() -> None:
    v_lead = np.clip(12.0 - 8.0 * np.clip(TIMES - 3.0, 0.0, None), 0.0, None)
    x_lead = 20.0 + np.concatenate([[0.0], np.cumsum(0.5 * (v_lead[1:] + v_lead[:-1]) * DT)])
    st = states([("lead", "vehicle", track(x_lead, 0.0), CAR), ("f", "vehicle", track(12.0 * TIMES, 0.0), CAR),
                 ("g", "vehicle", track(-30.0 + 11.0 * TIMES, 3.5), CAR)])
    one, two = rollout(st, ["lead"]), rollout(st, ["lead"])
    for name in ("xy", "z", "heading", "speed", "valid"):
        a, b, ref = getattr(one.states, name), getattr(two.states, name), getattr(st, name)
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a[0], ref[0])
        np.testing.assert_array_equal(a[:, :START], ref[:, :START])
    assert one.states.sources == two.states.sources
    # lane-graph routes (no log intent) also leave fixed rows alone
    lanes_only = rollout(st, ["lead"], use_log_routes=False)
    np.testing.assert_array_equal(lanes_only.states.xy[0], st.xy[0])
    assert not collides(lanes_only.states, 1)


# ------------------------------------------------------------------------------------------ (h) slow reference
def _reference_leaders(paths: list[Path], s: np.ndarray, half_len: np.ndarray, half_w: np.ndarray,
                       xy: np.ndarray, heading: np.ndarray, size: np.ndarray, margin: float,
                       ahead_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Per driven agent, a plain loop over every other agent with exact polyline projections."""
    gaps, leaders = np.full(len(paths), np.inf), np.full(len(paths), -1)
    for i, path in enumerate(paths):
        for j in range(len(xy)):
            if j == i:
                continue
            along, lat = project_points(path, xy[j][None])
            along_j, lat_j = float(along[0]), float(lat[0])
            if along_j <= s[i] or along_j > s[i] + ahead_m or along_j >= path.length:
                continue
            ext_along, ext_lat = box_extents(size[j, 0], size[j, 1], heading[j] - float(path.heading(along_j)))
            if abs(lat_j) >= half_w[i] + ext_lat + margin:
                continue
            gap = along_j - ext_along - (s[i] + half_len[i])
            if gap < gaps[i]:
                gaps[i], leaders[i] = gap, j
    return gaps, leaders


@pytest.mark.parametrize("seed", range(4))
def test_vectorised_leader_gaps_match_a_per_agent_loop(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 40
    paths, s, xy, heading = [], np.zeros(n), np.zeros((n, 2)), np.zeros(n)
    for i in range(n):  # gentle arcs and straight lines across a 120 m square
        start = rng.uniform(-60.0, 60.0, 2)
        yaw0 = rng.uniform(-np.pi, np.pi)
        curv = rng.choice([0.0, rng.uniform(-0.01, 0.01)])
        arc = np.arange(0.0, 200.0, 0.5)
        yaw = yaw0 + curv * arc
        pts = start + np.cumsum(np.stack([np.cos(yaw), np.sin(yaw)], 1) * 0.5, axis=0)
        paths.append(Path.from_points(pts))
        s[i] = rng.uniform(5.0, 40.0)
    grid = RouteGrid.from_paths(paths, 200.0, 1.0)
    xy, heading = grid.pose(s)
    # other agents scattered around, some near the routes: ``n`` driven plus 60 given ones
    anchor = rng.integers(0, n, 60)
    along = s[anchor] + rng.uniform(-10.0, 60.0, 60)
    base, yaw = grid.pose(along, rows=anchor)
    lateral = rng.uniform(-4.0, 4.0, 60)
    others = base + lateral[:, None] * np.stack([-np.sin(yaw), np.cos(yaw)], 1)
    all_xy = np.concatenate([xy, others])
    all_heading = np.concatenate([heading, yaw + rng.uniform(-0.5, 0.5, 60)])
    size = np.concatenate([np.tile([4.5, 2.0], (n, 1)), rng.uniform(0.5, 8.0, (60, 2))])
    half_len, half_w = np.full(n, 2.25), np.full(n, 1.0)
    margin, ahead, behind = 0.3, 70.0, 30.0
    width = int(np.ceil((ahead + behind) / grid.step)) + 1
    k0 = grid.window_start(s, behind, width)
    pairs = route_pairs(grid, k0, width, xy, np.arange(n), all_xy, all_heading, size, np.zeros_like(all_xy),
                        np.ones(len(all_xy), bool), 1e6)
    lead = nearest_ahead(pairs, s, half_len, half_w, np.zeros(len(pairs.i)), margin,
                         mask=pairs.along <= s[pairs.i] + ahead)
    ref_gap, ref_leader = _reference_leaders(paths, s, half_len, half_w, all_xy, all_heading, size, margin, ahead)
    assert (ref_leader >= 0).sum() > 5  # the scenes do have leaders
    same = lead.other == ref_leader
    assert same.mean() > 0.9  # leaders differ only at corridor borders / near ties
    both = same & (ref_leader >= 0)
    np.testing.assert_allclose(lead.gap[both], ref_gap[both], atol=0.05)
    np.testing.assert_array_equal(np.isinf(lead.gap[same]), np.isinf(ref_gap[same]))


# ------------------------------------------------------------------------------------------ (g) oncoming traffic
def test_an_oncoming_car_that_has_passed_is_no_leader_of_a_left_turn() -> None:
    """A car turns left across the westbound lane (y = 3.5) after an oncoming car has passed there: while the
    oncoming car comes towards it, it lies in the turning corridor but drives against it, a conflict to check by
    gap acceptance (it is clear well before the turn), not a leader to brake for."""
    v, radius, x_turn = 8.0, 10.0, 25.0
    s = v * TIMES
    ang = np.clip((s - x_turn) / radius, 0.0, np.pi / 2)
    x = np.where(s < x_turn, s, x_turn + radius * np.sin(ang))
    y = np.where(s < x_turn, 0.0, radius * (1.0 - np.cos(ang))) + np.clip(s - x_turn - radius * np.pi / 2, 0.0, None)
    oncoming = track(45.0 - v * TIMES, 3.5)
    st = states([("turner", "vehicle", track(x, y), CAR), ("oncoming", "vehicle", oncoming, CAR)])
    assert not collides(st, 0)
    out = rollout(st, ["oncoming"])
    assert not collides(out.states, 0) and feasible(out.states, 0)
    assert out.states.speed[0, START:].min() > 0.75 * v  # never braked for it


# ------------------------------------------------------------------------------------------ (i) steering
def test_a_waiting_car_keeps_its_heading_until_it_moves() -> None:
    """A car waiting askew to its lane (a heading the log gives, not its route's) turns into the lane only as
    it drives, at most ``max_curvature_per_m`` radians per metre: standing, it does not spin on the spot."""
    x = np.where(TIMES < 5.0, 0.0, 2.5 * (TIMES - 5.0) ** 2)  # waits, then pulls away at 5 m/s2
    waiting = track(x, 0.8)
    waiting["heading"] = np.full(T, -0.3)
    st = states([("ego", "vehicle", track(-80.0 + 10.0 * TIMES, 3.5), CAR), ("c", "vehicle", waiting, CAR)])
    out = rollout(st, ["ego"]).states
    heading, xy = out.heading[1, START - 1:], out.xy[1, START - 1:]
    travelled = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    limit = ReactivePredictor().params.route.max_curvature_per_m
    turned = np.abs(np.angle(np.exp(1j * np.diff(heading))))
    assert (turned <= limit * travelled + 1e-9).all()
    still = np.cumsum(travelled) < 0.05
    assert still.sum() > 10 and np.abs(heading[1:][still] + 0.3).max() < 0.02  # standing: as logged
    assert abs(heading[-1]) < 0.05  # driving: along the lane
