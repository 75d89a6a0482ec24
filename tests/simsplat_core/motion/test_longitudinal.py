"""IDM+ along the route: desired gap, interaction and free-road terms, the step, calibration to a logged gap,
and a follower closing on a standing obstacle that stops behind it."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.longitudinal import IDMArrays, desired_gap, free_accel, interaction_accel, next_speed
from simsplat_core.motion.traffic_params import IDMParams

P = IDMParams()  # T 1.5 s, s0 2 m, a 1.5, b 2, hard brake 8, clearance 0.5
DT = 0.1


def _one(params: IDMParams = P) -> IDMArrays:
    return IDMArrays.per_agent([params])


def _a(*values: float) -> np.ndarray:
    return np.array(values, dtype=np.float64)


def test_per_agent_stacks_each_agents_parameters() -> None:
    other = IDMParams(desired_time_headway_s=0.5, min_gap_m=0.4, max_accel_mps2=1.0, comfortable_decel_mps2=1.2,
                      max_decel_mps2=3.0, min_time_headway_s=0.2, min_standstill_gap_m=0.3, standstill_clearance_m=0.1)
    p = IDMArrays.per_agent([P, other])
    assert p.time_headway.tolist() == [1.5, 0.5] and p.min_gap.tolist() == [2.0, 0.4]
    assert p.max_accel.tolist() == [1.5, 1.0] and p.comfortable_decel.tolist() == [2.0, 1.2]
    assert p.max_decel.tolist() == [8.0, 3.0] and p.clearance.tolist() == [0.5, 0.1]
    assert p.min_time_headway.tolist() == [0.6, 0.2] and p.min_min_gap.tolist() == [1.0, 0.3]


def test_desired_gap() -> None:
    p = _one()
    assert desired_gap(_a(0.0), _a(0.0), p)[0] == pytest.approx(2.0)  # standstill: s0
    assert desired_gap(_a(10.0), _a(0.0), p)[0] == pytest.approx(2.0 + 10.0 * 1.5)  # same speed: s0 + v T
    closing = 2.0 + 15.0 + 10.0 * 5.0 / (2.0 * np.sqrt(1.5 * 2.0))
    assert desired_gap(_a(10.0), _a(5.0), p)[0] == pytest.approx(closing)
    assert desired_gap(_a(10.0), _a(-100.0), p)[0] == pytest.approx(2.0)  # leader pulling away fast: never below s0


def test_interaction_term() -> None:
    p = IDMArrays.per_agent([P] * 4)
    v, v_lead = np.full(4, 10.0), np.full(4, 10.0)
    s_star = 2.0 + 15.0
    a = interaction_accel(v, v_lead, _a(np.inf, s_star, 2.0 * s_star, s_star / 2.0), p)
    assert a[0] == pytest.approx(1.5)  # nobody ahead: a
    assert a[1] == pytest.approx(0.0)  # at the desired gap: no push either way
    assert a[2] == pytest.approx(1.5 * (1.0 - 0.25))
    assert a[3] == pytest.approx(1.5 * (1.0 - 4.0))  # half the desired gap: brakes


def test_free_road_term_tracks_the_logged_speed() -> None:
    p = _one()
    assert free_accel(_a(10.0), _a(10.0), _a(10.0), DT, p)[0] == pytest.approx(0.0)
    assert free_accel(_a(5.0), _a(10.0), _a(10.0), DT, p)[0] == pytest.approx(1.5)  # catches up at a
    # the log itself accelerates at 3 m/s^2: the agent may too
    assert free_accel(_a(5.0), _a(10.3), _a(10.0), DT, p)[0] == pytest.approx(3.0)
    assert free_accel(_a(10.0), _a(0.0), _a(0.0), DT, p)[0] == pytest.approx(-8.0)  # no harder than the hard brake
    assert free_accel(_a(10.0), _a(8.0), _a(9.0), DT, p)[0] == pytest.approx(-10.0)  # ... unless the log does


def test_a_step_never_reverses_or_enters_the_clearance() -> None:
    p = _one()
    assert next_speed(_a(0.5), _a(-8.0), DT, _a(np.inf), p)[0] == 0.0  # stops, does not reverse
    assert next_speed(_a(10.0), _a(-100.0), DT, _a(np.inf), p)[0] == pytest.approx(10.0 - 8.0 * DT)  # hard brake
    assert next_speed(_a(10.0), _a(1.0), DT, _a(np.inf), p)[0] == pytest.approx(10.1)
    # 0.8 m to the obstacle, 0.5 m clearance: at most 0.3 m this step whatever the acceleration
    assert next_speed(_a(10.0), _a(1.0), DT, _a(0.8), p)[0] == pytest.approx(0.3 / DT)
    assert next_speed(_a(10.0), _a(1.0), DT, _a(0.2), p)[0] == 0.0


def test_calibration_keeps_a_drivers_own_closer_gap() -> None:
    p = IDMArrays.per_agent([P] * 3)
    v, v_lead = np.full(3, 10.0), np.full(3, 10.0)
    gap = _a(12.0, np.inf, 3.0)  # closer than s0 + v T = 17 m; no leader; closer than the floors allow
    cal = p.calibrated(v, v_lead, gap)
    # 12 m at 10 m/s behind a leader at the same speed: s0 stays 2 m, T drops to 1 s -> no braking at that gap
    assert cal.min_gap[0] == pytest.approx(2.0) and cal.time_headway[0] == pytest.approx(1.0)
    assert interaction_accel(v[:1], v_lead[:1], gap[:1], IDMArrays.per_agent([P]).calibrated(
        v[:1], v_lead[:1], gap[:1]))[0] == pytest.approx(0.0)
    assert cal.time_headway[1] == pytest.approx(1.5) and cal.min_gap[1] == pytest.approx(2.0)  # unchanged
    assert cal.time_headway[2] == pytest.approx(0.6) and cal.min_gap[2] == pytest.approx(2.0)  # floored at 0.6 s
    standing = p.calibrated(np.zeros(3), np.zeros(3), _a(1.5, 0.5, 5.0))
    assert standing.min_gap.tolist() == pytest.approx([1.5, 1.0, 2.0])  # s0 between 1 m and 2 m
    assert standing.time_headway.tolist() == pytest.approx([1.5, 1.5, 1.5])  # at standstill T is not observed


def test_follower_stops_behind_a_standing_obstacle() -> None:
    """15 m/s, 80 m behind a standing car: IDM+ (free term at the logged 15 m/s) brings it to a stop at about s0
    behind it, never closer than the clearance and never harder than the hard-brake limit."""
    p = _one()
    v, gap = _a(15.0), _a(80.0)
    gaps, speeds = [], []
    for _ in range(int(60.0 / DT)):
        accel = np.minimum(free_accel(v, _a(15.0), _a(15.0), DT, p), interaction_accel(v, _a(0.0), gap, p))
        v_new = next_speed(v, accel, DT, gap, p)
        assert (v - v_new)[0] <= 8.0 * DT + 1e-9
        gap = gap - v_new * DT
        v = v_new
        gaps.append(gap[0])
        speeds.append(v[0])
    assert min(gaps) >= 0.5 - 1e-9
    assert speeds[-1] == pytest.approx(0.0, abs=0.05)
    assert gaps[-1] == pytest.approx(2.0, abs=0.5)
