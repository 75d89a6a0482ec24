"""Trajectory kinematics of the scenario layer: resampling, yaw rate and curvature on known paths."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.scenario.trajectory import curvature, moving_average, resample_series, smoothed_velocity, yaw_rate


def _circle(radius: float, speed: float, seconds: float = 4.0, hz: float = 10.0, left: bool = True):
    """Positions, headings and times of an agent driving a circle of ``radius`` at ``speed``."""
    t = np.arange(0.0, seconds, 1.0 / hz)
    sign = 1.0 if left else -1.0
    swept = speed * t / radius  # [T] angle travelled around the centre
    xy = np.stack([radius * np.sin(swept), sign * radius * (1.0 - np.cos(swept))], axis=1)
    return t, xy, sign * swept


@pytest.mark.parametrize("left", [True, False])
def test_curvature_of_a_circle_is_its_inverse_radius(left: bool) -> None:
    t, xy, heading = _circle(radius=20.0, speed=8.0, left=left)
    speed = np.linalg.norm(smoothed_velocity(t, xy, 0.5), axis=1)
    kappa = curvature(t, heading, speed, half_window_s=0.5)
    inner = slice(5, -5)  # the line fit is one-sided at the ends
    assert np.allclose(speed[inner], 8.0, rtol=0.02)
    assert np.allclose(kappa[inner], (1.0 if left else -1.0) / 20.0, rtol=0.02)


def test_yaw_rate_unwraps_headings_across_pi() -> None:
    t = np.arange(0.0, 3.0, 0.1)
    heading = np.angle(np.exp(1j * (3.0 + 0.5 * t)))  # wraps from +pi to -pi half way
    assert np.allclose(yaw_rate(t, heading, 0.5), 0.5, atol=1e-9)


def test_standing_agents_have_no_curvature() -> None:
    t = np.arange(0.0, 2.0, 0.1)
    jitter = np.random.default_rng(0).normal(0.0, 0.05, t.shape)
    assert np.all(curvature(t, jitter, np.zeros_like(t), 0.5) == 0.0)


def test_resample_series_interpolates_and_holds_the_ends() -> None:
    t = np.array([0.0, 1.0, 3.0])
    values = np.array([[0.0, 10.0], [1.0, 20.0], [3.0, 0.0]])
    out = resample_series(t, values, np.array([-1.0, 0.5, 2.0, 5.0]))
    assert np.allclose(out, [[0.0, 10.0], [0.5, 15.0], [2.0, 10.0], [3.0, 0.0]])
    assert np.allclose(resample_series(t[:1], values[:1], np.zeros(3)), np.repeat(values[:1], 3, axis=0))


def test_moving_average_is_centred_with_held_ends() -> None:
    np.testing.assert_allclose(moving_average(np.array([0.0, 0.0, 3.0, 0.0, 0.0]), 3), [0, 1, 1, 1, 0])
    np.testing.assert_allclose(moving_average(np.array([1.0, 4.0]), 3), [2.0, 3.0])  # ends held: (1+1+4)/3
    pts = np.stack([np.arange(6.0), np.full(6, 2.0)], axis=1)
    np.testing.assert_allclose(moving_average(pts, 3)[1:-1], pts[1:-1])  # a line stays a line inside
