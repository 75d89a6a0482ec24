"""Baseline predictors: log replay, and constant velocity from the last history step."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.baselines import NOT_OBSERVED, ConstantVelocityPredictor, LogReplayPredictor
from simsplat_core.motion.predictor import MotionPredictor, RolloutRequest
from tests.simsplat_core.motion.scenes import CAR, DT, PERSON, START, TIMES, T, road, states, track


def _request(fixed: list[int] | None = None, valid: dict[str, np.ndarray] | None = None) -> RolloutRequest:
    """ego (fixed by default) at 10 m/s; "acc" accelerating at 2 m/s^2 along +x; "diag" walking north-east at
    1.5 m/s; all logs stop at step 30 (invalid later)."""
    accel_x = 5.0 * TIMES + TIMES**2
    diag = 1.5 * TIMES / np.sqrt(2.0)
    until = np.arange(T) <= 30
    valid = {"ego": until, "acc": until, "diag": until, **(valid or {})}
    st = states([("ego", "vehicle", track(10.0 * TIMES, 3.5), CAR), ("acc", "vehicle", track(accel_x, 0.0), CAR),
                 ("diag", "pedestrian", {**track(diag, 0.0), "xy": np.stack([diag, diag], 1)}, PERSON)], valid)
    return RolloutRequest(st, START, np.array([0] if fixed is None else fixed, dtype=np.int64), road())


def test_log_replay_returns_the_request_states() -> None:
    predictor = LogReplayPredictor()
    assert isinstance(predictor, MotionPredictor) and predictor.name == "log"
    req = _request()
    out = predictor.rollout(req)
    assert out.states is req.states and out.replayed == {} and out.predictor == "log"


def test_constant_velocity_extrapolates_the_last_window_of_history() -> None:
    req = _request()
    out = ConstantVelocityPredictor().rollout(req)
    s, last = req.states, START - 1
    assert isinstance(ConstantVelocityPredictor(), MotionPredictor) and out.predictor == "constant-velocity"
    # "acc": velocity over the last 0.2 s of history (steps 8..10), extrapolated from its position at step 10
    v = (s.xy[1, last, 0] - s.xy[1, last - 2, 0]) / (2 * DT)
    assert v == pytest.approx(5.0 + TIMES[last] + TIMES[last - 2])  # x = 5 t + t^2: the mean speed over the window
    future = np.arange(START, T)
    np.testing.assert_allclose(out.states.xy[1, future, 0], s.xy[1, last, 0] + v * (TIMES[future] - TIMES[last]))
    np.testing.assert_allclose(out.states.xy[1, future, 1], 0.0)
    np.testing.assert_allclose(out.states.speed[1, future], v)
    np.testing.assert_allclose(out.states.heading[1, future], s.heading[1, last])
    assert out.states.valid[1:, START:].all()  # valid to the end although the log stops at step 30
    assert out.states.sources == ("log", "refined", "refined")
    # the walker keeps its north-east direction
    np.testing.assert_allclose(np.diff(out.states.xy[2, START:], axis=0), 1.5 * DT / np.sqrt(2.0), atol=1e-9)


def test_history_and_fixed_rows_are_kept() -> None:
    req = _request(fixed=[0, 2])
    out = ConstantVelocityPredictor().rollout(req)
    for name in ("xy", "heading", "speed", "valid", "z"):
        got, given = getattr(out.states, name), getattr(req.states, name)
        np.testing.assert_array_equal(got[[0, 2]], given[[0, 2]])
        np.testing.assert_array_equal(got[:, :START], given[:, :START])
    assert out.states.sources == ("log", "refined", "log")


def test_one_step_of_history_uses_the_stored_speed_along_the_heading() -> None:
    only_last = np.arange(T) == START - 1
    req = _request(valid={"acc": only_last})
    out = ConstantVelocityPredictor().rollout(req)
    s = req.states
    expected = s.xy[1, START - 1] + s.speed[1, START - 1] * DT * np.array([np.cos(s.heading[1, START - 1]),
                                                                           np.sin(s.heading[1, START - 1])])
    np.testing.assert_allclose(out.states.xy[1, START], expected)


def test_an_agent_missing_at_the_last_history_step_is_replayed_and_named() -> None:
    later = np.arange(T) >= START + 5
    req = _request(valid={"acc": later})
    out = ConstantVelocityPredictor().rollout(req)
    assert out.replayed == {"acc": NOT_OBSERVED}
    np.testing.assert_array_equal(out.states.xy[1], req.states.xy[1])
    np.testing.assert_array_equal(out.states.valid[1], later)
    assert out.states.sources[1] == "log"
