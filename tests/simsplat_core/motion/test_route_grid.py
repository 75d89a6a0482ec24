"""Routes on one arc-length grid: poses, windows and projections on a straight route and on a bend."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.route_grid import RouteGrid
from simsplat_core.scenario.path import Path

RADIUS = 20.0


def _straight() -> Path:
    return Path.from_points(np.array([[0.0, 0.0], [100.0, 0.0]]))


def _left_bend() -> Path:
    """A quarter circle of radius 20 m turning left from (0, 0) heading +x, centre (0, 20)."""
    ang = np.linspace(0.0, np.pi / 2, 200)
    return Path.from_points(np.stack([RADIUS * np.sin(ang), RADIUS - RADIUS * np.cos(ang)], 1))


def test_from_paths_samples_every_step_and_extrapolates_straight() -> None:
    grid = RouteGrid.from_paths([_straight()], 150.0, 2.0)
    assert grid.num_points == int(np.ceil(150.0 / 2.0)) + 2
    np.testing.assert_allclose(grid.x[0], np.arange(grid.num_points) * 2.0)  # past the path's end too
    np.testing.assert_allclose(grid.y[0], 0.0)
    empty = RouteGrid.from_paths([], 10.0, 1.0)
    assert empty.x.shape == (0, 12)


def test_pose_interpolates_between_grid_points() -> None:
    grid = RouteGrid.from_paths([_straight(), _left_bend()], 40.0, 1.0)
    xy, yaw = grid.pose(np.array([12.25, RADIUS * np.pi / 4]))
    assert xy[0].tolist() == pytest.approx([12.25, 0.0]) and yaw[0] == pytest.approx(0.0)
    half_way = [RADIUS * np.sin(np.pi / 4), RADIUS - RADIUS * np.cos(np.pi / 4)]
    assert xy[1].tolist() == pytest.approx(half_way, abs=0.02) and yaw[1] == pytest.approx(np.pi / 4, abs=0.01)
    # one route queried at several arc lengths: rows pick it
    xy, _ = grid.pose(np.array([[1.0, 2.0, 3.0]]), rows=np.array([0]))
    assert xy.shape == (1, 3, 2) and xy[0, :, 0].tolist() == pytest.approx([1.0, 2.0, 3.0])


def test_window_start_is_clipped_to_the_grid() -> None:
    grid = RouteGrid.from_paths([_straight()] * 3, 100.0, 1.0)
    k0 = grid.window_start(np.array([5.0, 50.0, 99.0]), behind_m=10.0, width=20)
    assert k0.tolist() == [0, 40, grid.num_points - 20]


def test_project_on_a_straight_route_is_exact() -> None:
    grid = RouteGrid.from_paths([_straight()], 100.0, 1.0)
    k0 = grid.window_start(np.array([10.0]), 10.0, 60)
    along, lateral, yaw = grid.project(np.array([0]), k0, 60, np.array([[[12.3, -0.7], [40.0, 2.0]]]))
    assert along[0].tolist() == pytest.approx([12.3, 40.0])
    assert lateral[0].tolist() == pytest.approx([-0.7, 2.0])  # left positive
    assert yaw[0].tolist() == pytest.approx([0.0, 0.0])


def test_project_on_a_bend_within_the_grids_tolerance() -> None:
    grid = RouteGrid.from_paths([_left_bend()], 40.0, 1.0)
    k0 = grid.window_start(np.array([0.0]), 0.0, 35)
    ang = np.array([0.3, 0.7, 1.2])
    inside = (RADIUS - 1.5) * np.stack([np.sin(ang), -np.cos(ang)], 1) + [0.0, RADIUS]  # 1.5 m inside the turn
    along, lateral, yaw = grid.project(np.array([0]), k0, 35, inside[None])
    assert along[0].tolist() == pytest.approx((RADIUS * ang).tolist(), abs=0.1)
    assert lateral[0].tolist() == pytest.approx([1.5] * 3, abs=0.05)  # inside a left turn: to the left
    assert yaw[0].tolist() == pytest.approx(ang.tolist(), abs=0.03)


def test_each_query_projects_onto_its_own_route() -> None:
    shifted = Path.from_points(np.array([[0.0, 10.0], [100.0, 10.0]]))
    grid = RouteGrid.from_paths([_straight(), shifted], 100.0, 1.0)
    k0 = grid.window_start(np.array([0.0, 0.0]), 0.0, 50)
    point = np.array([[[20.0, 4.0]], [[20.0, 4.0]]])
    _, lateral, _ = grid.project(np.array([0, 1]), k0, 50, point)
    assert lateral[:, 0].tolist() == pytest.approx([4.0, -6.0])
