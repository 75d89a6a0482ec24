"""The bird's-eye animation: frame sampling, the shared view, the playback rate."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.viz.bev import EGO_COLOR, REFINED_COLOR
from simsplat_core.viz.bev_animation import bev_animation_frames, bev_fps
from tests.simsplat_core.viz.scenes import T, color_mask, straight_agents

SIZE = 120


def _scenario() -> tuple[AgentStates, AgentStates]:
    """The ego on y = 0 and a car on y = -6 (to the ego's right), both eastbound; the car reacts (refined) by
    stopping at step 5."""
    before = straight_agents(("ego", "car"), ("log", "log"), [(0.0, 0.0), (5.0, -6.0)])
    xy = before.xy.copy()
    xy[1, 5:] = xy[1, 5]
    after = dataclasses.replace(before, sources=("log", "refined"), xy=xy)
    return before, after


@pytest.mark.parametrize(("every", "count"), [(1, T), (3, 7), (0, T), (T + 5, 1)])
def test_one_frame_per_every_th_step(every: int, count: int) -> None:
    before, after = _scenario()
    frames = bev_animation_frames([], before, after, size=SIZE, every=every)
    assert len(frames) == count
    assert all(f.shape == (SIZE, 2 * SIZE, 3) and f.dtype == np.uint8 for f in frames)


def test_both_panels_share_one_view_and_a_white_seam() -> None:
    before, after = _scenario()
    for frame in bev_animation_frames([], before, after, size=SIZE, every=4):
        left, right = frame[:, :SIZE], frame[:, SIZE:]
        assert (left[:, -2:] == 255).all()
        # the ego, unchanged, is drawn on the same pixels in both panels (between the title and the footer)
        body = slice(24, SIZE - 20)
        np.testing.assert_array_equal(color_mask(left[body, :-2], EGO_COLOR), color_mask(right[body, :-2], EGO_COLOR))


def test_the_reacting_car_stops_on_the_right_and_drives_on_on_the_left() -> None:
    before, after = _scenario()
    size = 2 * SIZE  # boxes big enough to have a filled inside
    frames = bev_animation_frames([], before, after, size=size, every=1)
    fill = tuple(int(c * 0.5) for c in REFINED_COLOR)

    def box_row(panel: np.ndarray) -> float:
        rows = np.flatnonzero(color_mask(panel, fill).any(axis=1))
        return float(rows.mean())

    rows = [box_row(f[:, size:]) for f in frames]
    assert rows[0] > rows[5]  # moving up the picture (world +x) until step 5
    assert rows[5] == rows[10] == rows[-1]  # then standing
    assert not color_mask(frames[10][:, :size], fill).any()  # the log has no reacting agent


def _first_steps(states: AgentStates, n: int) -> AgentStates:
    return dataclasses.replace(states, frame_idx=states.frame_idx[:n], times=states.times[:n], xy=states.xy[:, :n],
                               z=states.z[:, :n], heading=states.heading[:, :n], speed=states.speed[:, :n],
                               valid=states.valid[:, :n])


def test_mismatched_steps_are_an_error() -> None:
    before, after = _scenario()
    with pytest.raises(ValueError, match=f"before has 5 steps, after {T}"):
        bev_animation_frames([], _first_steps(before, 5), after)


def test_fps_plays_in_real_time() -> None:
    before, _ = _scenario()
    assert bev_fps(before) == pytest.approx(10.0)
    assert bev_fps(dataclasses.replace(before, times=before.times / 2.0)) == pytest.approx(20.0)
    assert bev_fps(dataclasses.replace(before, times=np.zeros(T))) == 10.0  # no time on the steps
    assert bev_fps(_first_steps(before, 1)) == 10.0  # a single step
