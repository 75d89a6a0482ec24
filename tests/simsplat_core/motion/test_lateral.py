"""Lateral offset profiles over arc length and the MOBIL lane-change decision."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.lateral import OffsetProfiles, change_length, mobil_gain


def _profiles() -> OffsetProfiles:
    """Agent 0 moves from 0 to +3.5 m (left) over s in [10, 30]; agent 1 fades -1 m out over s in [0, 5]."""
    return OffsetProfiles(start=np.array([10.0, 0.0]), length=np.array([20.0, 5.0]), origin=np.array([0.0, -1.0]),
                          target=np.array([3.5, 0.0]))


def test_offset_is_a_smoothstep_from_origin_to_target() -> None:
    p = _profiles()
    rows = np.zeros(5, int)
    off = p.offset(rows, np.array([0.0, 10.0, 20.0, 30.0, 50.0]))
    assert off.tolist() == pytest.approx([0.0, 0.0, 1.75, 3.5, 3.5])  # half way at the middle
    s = np.linspace(10.0, 30.0, 201)
    assert np.all(np.diff(p.offset(np.zeros_like(s, int), s)) >= 0)  # monotone
    assert p.offset(np.array([1]), np.array([2.5]))[0] == pytest.approx(-0.5)


def test_slope_is_the_derivative_flat_at_both_ends() -> None:
    p = _profiles()
    s = np.linspace(9.0, 31.0, 441)
    rows = np.zeros_like(s, int)
    numeric = np.gradient(p.offset(rows, s), s)
    np.testing.assert_allclose(p.slope(rows, s)[1:-1], numeric[1:-1], atol=2e-3)
    assert p.slope(np.array([0, 0]), np.array([10.0, 30.0])).tolist() == pytest.approx([0.0, 0.0])
    assert p.slope(np.array([0]), np.array([20.0]))[0] == pytest.approx(3.5 * 1.5 / 20.0)  # steepest at the middle


def test_settled_and_replace() -> None:
    p = _profiles()
    assert p.settled(np.array([29.0, 5.0])).tolist() == [False, True]
    p.replace(np.array([1]), np.array([40.0]), np.array([10.0]), np.array([0.0]), np.array([-3.5]))
    assert p.offset(np.array([1, 1, 0]), np.array([40.0, 50.0, 50.0])).tolist() == pytest.approx([0.0, -3.5, 3.5])
    assert not p.settled(np.array([50.0, 45.0]))[1]


def test_mobil_gain_counts_only_the_new_followers_loss() -> None:
    # own gain 1 - (-2) = 3; the new follower loses 1.5 - 0.5 = 1, weighted by politeness 0.3
    assert mobil_gain(np.array([-2.0]), np.array([1.0]), np.array([1.5]), np.array([0.5]), 0.3)[0] == \
        pytest.approx(2.7)
    # a follower that would not have to brake at all costs nothing
    assert mobil_gain(np.array([-2.0]), np.array([1.0]), np.array([1.5]), np.array([1.5]), 0.3)[0] == \
        pytest.approx(3.0)
    assert mobil_gain(np.array([0.0]), np.array([0.0]), np.array([1.5]), np.array([-3.0]), 0.0)[0] == 0.0


def test_change_length_must_end_before_the_obstacle() -> None:
    v = np.array([10.0, 10.0, 10.0, 1.0])
    gap = np.array([100.0, 25.0, 10.0, 100.0])
    length = change_length(v, gap, duration_s=3.0, min_length_m=10.0, clearance_m=2.0)
    assert length[0] == pytest.approx(30.0)  # v * duration
    assert length[1] == pytest.approx(23.0)  # shortened to end 2 m before the obstacle 25 m ahead
    assert np.isnan(length[2])  # 8 m of room: shorter than the 10 m minimum, no change
    assert length[3] == pytest.approx(10.0)  # slow: never less road than the minimum
