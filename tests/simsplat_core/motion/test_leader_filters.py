"""The leader filters and the log-based fixes of the reactive predictor, on hand-built scenes: each with a scene
where the old rule stopped an agent and one where a real blocker still stops it."""

from __future__ import annotations

import dataclasses

import numpy as np

from simsplat_core.motion.leader_filters import mutual_leaders
from simsplat_core.motion.predictor import RolloutRequest
from simsplat_core.motion.reactive import ReactivePredictor
from simsplat_core.motion.routes import PARKED_JITTER, plan_routes
from simsplat_core.motion.traffic_params import ReactiveParams
from simsplat_core.scenario.agents import AgentStates
from tests.simsplat_core.motion.scenes import CAR, PERSON, START, TIMES, T, road, states, track

DEFAULT = ReactiveParams()
NO_COMPANY = dataclasses.replace(DEFAULT, corridor=dataclasses.replace(DEFAULT.corridor, company_gap_m=0.0))
NO_PASSING = dataclasses.replace(DEFAULT, corridor=dataclasses.replace(DEFAULT.corridor, parked_move_m=0.0))


def run(st: AgentStates, params: ReactiveParams = DEFAULT, fixed: tuple[str, ...] = ("ego",)) -> AgentStates:
    req = RolloutRequest(st, START, np.array([st.index(o) for o in fixed], dtype=np.int64), road())
    return ReactivePredictor(params).rollout(req).states


def travelled(st: AgentStates, oid: str) -> float:
    r = st.index(oid)
    return float(np.linalg.norm(np.diff(st.xy[r, START - 1:], axis=0), axis=1).sum())


EGO = ("ego", "vehicle", track(-200.0 + 0.0 * TIMES, 3.5), CAR)


# ------------------------------------------------------------------------------------------ parked jitter
def test_a_parked_box_that_jitters_is_replayed_and_a_slow_mover_is_driven() -> None:
    rng = np.random.default_rng(0)
    jitter = track(30.0 + rng.uniform(-1.5, 1.5, T), 3.5)
    jitter["speed"] = np.zeros(T)  # the log's own speed says parked
    mover = track(0.2 * TIMES, 0.0)  # 1.8 m over the log, slow but real
    mover["speed"] = np.full(T, 0.5)
    st = states([EGO, ("parked", "vehicle", jitter, CAR), ("slow", "vehicle", mover, CAR)])
    req = RolloutRequest(st, START, np.array([0]), road())
    plan = plan_routes(req, DEFAULT.route, DEFAULT.pedestrian)
    assert plan.replayed.get(st.index("parked")) == PARKED_JITTER
    assert st.index("slow") in {r.row for r in plan.routes}
    out = run(st)
    assert np.allclose(out.xy[st.index("parked")], st.xy[st.index("parked")])


# ------------------------------------------------------------------------------------------ parked obstacles passed
def _passing_scene(obstacle_source: str = "log") -> AgentStates:
    """A car driving 10 m/s in lane 0 past a car parked at x = 40 whose box reaches 0.2 m into its corridor."""
    st = states([EGO, ("car", "vehicle", track(10.0 * TIMES, 0.0), CAR),
                 ("parked", "vehicle", track(np.full(T, 40.0), 2.1), CAR)])
    return dataclasses.replace(st, sources=("log", "log", obstacle_source))


def test_an_unedited_car_drives_past_the_parked_car_its_log_passes() -> None:
    st = _passing_scene()
    log_path = travelled(st, "car")
    assert travelled(run(st, NO_PASSING), "car") < 0.6 * log_path  # the old rule: it stops behind it
    assert travelled(run(st), "car") > 0.95 * log_path


def test_an_inserted_parked_car_still_stops_the_unedited_car() -> None:
    st = _passing_scene("inserted")
    out = run(st, fixed=("ego", "parked"))
    assert travelled(out, "car") < 0.6 * travelled(st, "car")


# ------------------------------------------------------------------------------------------ travelling in company
def _walkers(front_speed: float) -> AgentStates:
    """Two pedestrians 0.8 m apart on the kerb line, the rear one walking 1.4 m/s, the front one ``front_speed``."""
    return states([EGO, ("rear", "pedestrian", track(-20.0 + 1.4 * TIMES, 6.0), PERSON),
                   ("front", "pedestrian", track(-19.2 + front_speed * TIMES, 6.0), PERSON)])


def test_pedestrians_walking_together_do_not_hold_each_other_back() -> None:
    st = _walkers(1.4)
    rear = st.index("rear")
    old = run(st, NO_COMPANY)
    new = run(st)
    dev_old = np.linalg.norm(old.xy[rear, START:] - st.xy[rear, START:], axis=1).max()
    dev_new = np.linalg.norm(new.xy[rear, START:] - st.xy[rear, START:], axis=1).max()
    assert dev_old > 0.5
    assert dev_new < 0.2


def test_a_pedestrian_standing_ahead_still_stops_the_walker() -> None:
    st = states([EGO, ("rear", "pedestrian", track(-20.0 + 1.4 * TIMES, 6.0), PERSON),
                 ("front", "pedestrian", track(np.full(T, -5.0), 6.0), PERSON)])
    out = run(st, fixed=("ego", "front"))
    rear = st.index("rear")
    assert out.xy[rear, -1, 0] < -5.0 - PERSON[0]  # never walks through the standing one


def test_a_walker_squeezes_past_the_standing_pedestrian_its_log_passes() -> None:
    """The walker's logged path runs through a person standing on the kerb line (their boxes touch as it
    passes): an unedited walker passes as logged, where a parked car in the same place would stop it."""
    walker = ("walker", "pedestrian", track(-20.0 + 1.4 * TIMES, 6.0), PERSON)
    st = states([EGO, walker, ("standing", "pedestrian", track(np.full(T, -14.0), 6.2), PERSON)])
    log_path = travelled(st, "walker")
    assert travelled(run(st, NO_PASSING), "walker") < 0.6 * log_path
    assert travelled(run(st), "walker") > 0.95 * log_path
    car = states([EGO, walker, ("parked", "vehicle", track(np.full(T, -14.0), 6.2), CAR)])
    assert travelled(run(car), "walker") < 0.6 * log_path


# ------------------------------------------------------------------------------------------ mutual leaders
def test_mutual_leaders_release_one_of_the_pair_only() -> None:
    rows = np.array([3, 5, 7])  # driven agents' rows
    driven_of = np.full(8, -1)
    driven_of[rows] = np.arange(3)
    leader = np.array([5, 3, 3])  # 3 <-> 5 mutual, 7 follows 3
    assert mutual_leaders(leader, driven_of, rows).tolist() == [True, False, False]
    assert not mutual_leaders(np.array([5, -1, 3]), driven_of, rows).any()


# ------------------------------------------------------------------------------------------ acceleration from the log
def test_acceleration_cap_follows_what_the_log_shows() -> None:
    brisk = 0.5 * 2.5 * np.clip(TIMES - 1.5, 0.0, 4.0) ** 2 + 10.0 * np.clip(TIMES - 5.5, 0.0, None)
    st = states([EGO, ("brisk", "vehicle", track(brisk, 0.0), CAR), ("steady", "vehicle", track(8.0 * TIMES, 3.5), CAR),
                 ("walker", "pedestrian", track(1.0 * TIMES, 6.0), PERSON)])
    req = RolloutRequest(st, START, np.array([0]), road())
    predictor = ReactivePredictor()
    drv = predictor._driven(req, plan_routes(req, DEFAULT.route, DEFAULT.pedestrian))
    accel = dict(zip([st.object_ids[r] for r in drv.rows], drv.idm.max_accel.tolist(), strict=True))
    assert 2.2 < accel["brisk"] <= DEFAULT.idm.log_accel_cap_mps2
    assert accel["steady"] == DEFAULT.idm.max_accel_mps2
    assert accel["walker"] == DEFAULT.pedestrian.following.max_accel_mps2
