"""MOBIL's safety check of an edited lane change (``editing.motion.merge_gap``) on hand-built straight-road motions."""

from __future__ import annotations

import numpy as np

from simsplat_core.editing.motion.merge_gap import unsafe_merge
from simsplat_core.scenario.agents import AgentStates

T = 40
DT = 0.1
TIMES = np.arange(T) * DT
CAR = np.array([4.5, 2.0, 1.5])


def _follower(x0: float, v: float = 10.0) -> AgentStates:
    """One car in the left lane (y = 3.5) heading east at ``v`` m/s from ``x0``."""
    xy = np.stack([x0 + v * TIMES, np.full(T, 3.5)], axis=1)[None]
    return AgentStates(object_ids=("f",), categories=("vehicle",), sources=("log",), node_ids=np.full(1, -1),
                       frame_idx=np.arange(T), times=TIMES.copy(), xy=xy, z=np.zeros((1, T)),
                       heading=np.zeros((1, T)), speed=np.full((1, T), v), size=CAR[None].copy(),
                       valid=np.ones((1, T), bool))


def _lane_change(x0: float, v: float = 10.0, y0: float = 0.0) -> tuple[np.ndarray, ...]:
    """A car from ``(x0, y0)`` at ``v`` m/s moving to y = 3.5 between 0.5 s and 2.5 s: ``xy, heading, speed,
    valid``."""
    y = y0 + (3.5 - y0) * np.clip((TIMES - 0.5) / 2.0, 0.0, 1.0)
    xy = np.stack([x0 + v * TIMES, y], axis=1)
    heading = np.arctan2(np.gradient(y, DT), v)
    return xy, heading, np.full(T, v), np.ones(T, bool)


def test_cutting_in_right_in_front_of_a_follower_squeezes_it() -> None:
    states = _follower(0.0)
    hit = unsafe_merge(states, *_lane_change(3.0), CAR, ("planned",), 0)
    assert hit is not None and hit[0] == 0 and 5 <= hit[1] <= 25  # while moving over


def test_a_lane_change_with_room_ahead_of_the_follower_is_fine() -> None:
    states = _follower(0.0)
    assert unsafe_merge(states, *_lane_change(35.0), CAR, ("planned",), 0) is None


def test_a_car_already_ahead_in_the_lane_is_not_cutting_in() -> None:
    states = _follower(0.0)
    assert unsafe_merge(states, *_lane_change(8.0, y0=3.5), CAR, ("planned",), 0) is None
    assert unsafe_merge(states, *_lane_change(3.0), CAR, ("f",), 0) is None  # excluded


def test_merging_right_behind_a_vehicle_is_unsafe_for_the_merging_car() -> None:
    states = _follower(0.0)
    hit = unsafe_merge(states, *_lane_change(-5.0), CAR, ("planned",), 0)  # its front 0.5 m from the other's rear
    assert hit is not None and hit[0] == 0
    assert unsafe_merge(states, *_lane_change(-40.0), CAR, ("planned",), 0) is None  # far behind: a gap
