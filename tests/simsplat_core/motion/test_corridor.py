"""Other agents seen from a driven agent's route: candidate pairs, the corridor, the nearest one ahead and behind."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.corridor import (
    box_extents,
    group_min,
    in_corridor,
    nearest_ahead,
    nearest_behind,
    route_pairs,
)
from simsplat_core.motion.route_grid import RouteGrid
from simsplat_core.scenario.path import Path

HALF_LEN, HALF_W, MARGIN = 2.25, 1.0, 0.3
CAR = (4.5, 2.0)


def test_box_extents_turn_with_the_box() -> None:
    along, across = box_extents(np.array([4.0, 4.0, 4.0]), np.array([2.0, 2.0, 2.0]),
                                np.array([0.0, np.pi / 2, np.pi / 4]))
    assert along.tolist() == pytest.approx([2.0, 1.0, 6.0 / (2.0 * np.sqrt(2.0))])
    assert across.tolist() == pytest.approx([1.0, 2.0, 6.0 / (2.0 * np.sqrt(2.0))])


def test_group_min_picks_each_groups_smallest_value() -> None:
    groups = np.array([0, 0, 2, 2, 2, 0])
    values = np.array([5.0, 3.0, np.inf, 1.0, 1.0, 3.0])
    best, idx = group_min(groups, values, 4)
    assert best.tolist() == [3.0, np.inf, 1.0, np.inf]
    assert idx.tolist() == [1, -1, 3, -1]  # ties: the lower index; groups without a finite value: -1


def _scene(others: list[tuple[float, float, float, float]], s: float = 10.0):
    """One driven car at arc length ``s`` of a straight eastbound route along y = 0 (agent 0), and others
    ``(x, y, heading, speed)`` (agents 1..), all car-sized."""
    grid = RouteGrid.from_paths([Path.from_points(np.array([[0.0, 0.0], [200.0, 0.0]]))], 200.0, 1.0)
    width = 101
    k0 = grid.window_start(np.array([s]), 30.0, width)
    xy = np.array([[s, 0.0]] + [[x, y] for x, y, _, _ in others])
    heading = np.array([0.0] + [h for _, _, h, _ in others])
    speed = np.array([0.0] + [v for _, _, _, v in others])
    velocity = speed[:, None] * np.stack([np.cos(heading), np.sin(heading)], 1)
    size = np.tile(CAR, (len(xy), 1))
    pairs = route_pairs(grid, k0, width, xy[:1], np.array([0]), xy, heading, size, velocity,
                        np.ones(len(xy), bool), reach_m=60.0)
    return pairs, np.array([s])


def test_route_pairs_hold_each_others_route_geometry() -> None:
    pairs, _ = _scene([(30.0, 1.0, np.pi / 2, 4.0), (100.0, 0.0, 0.0, 5.0), (25.0, -2.0, np.pi, 6.0)])
    assert pairs.i.tolist() == [0, 0] and pairs.j.tolist() == [1, 3]  # itself and the car 90 m away left out
    assert pairs.along.tolist() == pytest.approx([30.0, 25.0]) and pairs.lateral.tolist() == pytest.approx([1.0, -2.0])
    assert pairs.ext_along.tolist() == pytest.approx([1.0, 2.25])  # the crossing car shows its width
    assert pairs.v_along.tolist() == pytest.approx([0.0, -6.0], abs=1e-9)  # oncoming: negative


def test_the_leader_is_the_nearest_agent_in_the_corridor_ahead() -> None:
    pairs, s = _scene([(40.0, 0.5, 0.0, 8.0), (25.0, 3.5, 0.0, 8.0), (60.0, 0.0, 0.0, 9.0), (5.0, 0.0, 0.0, 9.0)])
    lead = nearest_ahead(pairs, s, np.array([HALF_LEN]), np.array([HALF_W]), np.zeros(len(pairs.i)), MARGIN)
    assert lead.other.tolist() == [1]  # the car in the next lane is nearer but outside the corridor
    assert lead.gap[0] == pytest.approx(40.0 - 2.25 - (10.0 + 2.25))  # bumper to bumper
    assert lead.speed[0] == pytest.approx(8.0)
    # shifted one lane to the left (a lane change), the car in the next lane leads
    shifted = nearest_ahead(pairs, s, np.array([HALF_LEN]), np.array([HALF_W]), np.full(len(pairs.i), 3.5), MARGIN)
    assert shifted.other.tolist() == [2]
    masked = nearest_ahead(pairs, s, np.array([HALF_LEN]), np.array([HALF_W]), np.zeros(len(pairs.i)), MARGIN,
                           mask=pairs.j != 1)
    assert masked.other.tolist() == [3]


def test_the_follower_is_the_nearest_agent_in_the_corridor_behind() -> None:
    pairs, s = _scene([(-5.0, 0.0, 0.0, 7.0), (2.0, 0.2, 0.0, 6.0), (40.0, 0.0, 0.0, 8.0)])
    behind = nearest_behind(pairs, s, np.array([HALF_LEN]), np.array([HALF_W]), np.zeros(len(pairs.i)), MARGIN)
    assert behind.other.tolist() == [2]
    assert behind.gap[0] == pytest.approx((10.0 - 2.25) - (2.0 + 2.25)) and behind.speed[0] == pytest.approx(6.0)


def test_no_one_in_the_corridor() -> None:
    pairs, s = _scene([(40.0, -3.5, 0.0, 8.0)])
    assert not in_corridor(pairs, np.array([HALF_W]), np.zeros(1), MARGIN).any()
    lead = nearest_ahead(pairs, s, np.array([HALF_LEN]), np.array([HALF_W]), np.zeros(1), MARGIN)
    assert lead.gap.tolist() == [np.inf] and lead.other.tolist() == [-1] and lead.speed.tolist() == [0.0]
    # the corridor's edge: half widths (1.0 + 1.0) plus the margin
    assert in_corridor(pairs, np.array([HALF_W]), np.full(1, -3.5 + 2.29), MARGIN).all()
    assert not in_corridor(pairs, np.array([HALF_W]), np.full(1, -3.5 + 2.31), MARGIN).any()
