"""Windows of a fixed length and rate cut from logs of any length and rate."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.export.windows import ExportLayout, at_layout_rate, plan_windows, sample_states
from simsplat_core.scenario.agents import AgentStates


def test_a_womd_length_log_is_one_window_of_its_own_frames() -> None:
    times = np.arange(91) * 0.1 + np.random.default_rng(0).uniform(-0.003, 0.003, 91)  # Waymo-like jitter
    times.sort()
    plan = plan_windows(times, ExportLayout())
    assert len(plan.windows) == 1 and not plan.resampled and plan.notes == ()
    np.testing.assert_array_equal(plan.windows[0].source, np.arange(91))
    np.testing.assert_array_equal(plan.windows[0].times, times)


def test_a_longer_log_is_cut_with_the_future_horizon_as_stride_and_no_step_is_dropped() -> None:
    plan = plan_windows(np.arange(110) * 0.1, ExportLayout())
    assert [w.source[0] for w in plan.windows] == [0, 80]
    covered = np.unique(np.concatenate([w.source[~np.isnan(w.source)] for w in plan.windows]))
    np.testing.assert_array_equal(covered, np.arange(110))
    last = plan.windows[-1]
    assert last.padded_steps == 61 and np.all(np.diff(last.times) > 0)
    assert any("2 windows" in n for n in plan.notes) and any("61 invalid" in n for n in plan.notes)


def test_a_short_log_is_padded_not_truncated() -> None:
    plan = plan_windows(np.arange(40) * 0.1, ExportLayout())
    (window,) = plan.windows
    assert window.padded_steps == 51 and np.isnan(window.source[40:]).all()
    np.testing.assert_allclose(np.diff(window.times), 0.1)


def test_another_rate_is_resampled_onto_the_layout_grid() -> None:
    times = np.arange(100) * 0.05  # 20 Hz
    plan = plan_windows(times, ExportLayout())
    assert plan.resampled and "resampled from 20.00 Hz" in plan.notes[0]
    window = plan.windows[0]
    np.testing.assert_allclose(window.source[:50], np.arange(50) * 2.0)
    assert not at_layout_rate(times, ExportLayout()) and at_layout_rate(times, ExportLayout(hz=20.0))


def test_stride_and_layout_are_checked() -> None:
    assert [w.source[0] for w in plan_windows(np.arange(120) * 0.1, ExportLayout(stride=20)).windows] == [0, 20, 40]
    with pytest.raises(ValueError, match="current_index"):
        ExportLayout(steps=5, current_index=5)
    with pytest.raises(ValueError, match="stride"):
        ExportLayout(stride=0)


def _states(heading: np.ndarray) -> AgentStates:
    t = heading.size
    return AgentStates(object_ids=("a",), categories=("vehicle",), sources=("log",), node_ids=np.array([-1]),
                       frame_idx=np.arange(t), times=np.arange(t) * 0.1,
                       xy=np.stack([np.arange(t, dtype=float), np.zeros(t)], 1)[None], z=np.ones((1, t)),
                       heading=heading[None], speed=np.full((1, t), 10.0), size=np.array([[4.0, 2.0, 1.5]]),
                       valid=np.array([[True, True, False, True]]))


def test_sampling_interpolates_positions_and_headings_across_the_wrap() -> None:
    states = _states(np.array([3.1, -3.1, 0.0, 0.0]))
    sampled = sample_states(states, np.array([0.5, 1.0, 1.5, np.nan]))
    np.testing.assert_allclose(sampled.xy[0, :2, 0], [0.5, 1.0])
    assert abs(abs(sampled.heading[0, 0]) - np.pi) < 1e-9  # half-way the short way round, not through 0
    np.testing.assert_array_equal(sampled.valid[0], [True, True, False, False])  # frame 2 invalid, padding invalid
