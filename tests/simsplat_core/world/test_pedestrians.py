"""Pedestrians are non-rigid: their limbs swing with the walk phase."""

from __future__ import annotations

import numpy as np

from simsplat_core.geometry import pose_from_yaw
from simsplat_core.world import WorldConfig, generate_world
from simsplat_core.world.config import CameraSpec
from simsplat_core.world.render import DrawList, camera_intrinsics, camera_to_ego, render_view


def _rigid_residual(a: np.ndarray, b: np.ndarray) -> float:
    """Largest point error of the best rigid fit (Kabsch) of point set ``a [N, 3]`` onto ``b [N, 3]``."""
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return float(np.linalg.norm((a - ca) @ rot.T + cb - b, axis=1).max())


def _walkers(world):
    return [a for a in world.agents if a.category == "pedestrian" and a.traj["speed"].max() > 0.5]


def test_walking_pedestrian_limbs_move_non_rigidly():
    world = generate_world(7, WorldConfig(num_frames=12))
    walkers = _walkers(world)
    assert walkers
    for agent in walkers:
        moving = np.nonzero(agent.traj["speed"] > 0.5)[0]
        assert len(moving) >= 6
        first = agent.world_mesh(int(moving[0])).tris.reshape(-1, 3)
        residuals = [_rigid_residual(first, agent.world_mesh(int(f)).tris.reshape(-1, 3)) for f in moving[1:6]]
        assert max(residuals) > 0.1, agent.object_id  # limbs move by decimetres within half a second
        for f in moving[:6]:  # the box still contains every posed vertex
            local = agent.local_mesh(int(f)).tris.reshape(-1, 3)
            assert np.all(np.abs(local[:, :2]) <= np.asarray(agent.size[:2]) / 2 + 1e-9)
    standers = [a for a in world.agents if a.category == "pedestrian" and a.traj["speed"].max() == 0.0]
    for agent in standers:
        assert _rigid_residual(agent.world_mesh(0).tris.reshape(-1, 3), agent.world_mesh(5).tris.reshape(-1, 3)) < 1e-9


def test_rendered_silhouette_changes_with_walk_phase():
    """Seen side-on from a fixed camera, the mask changes shape (not just position) across the gait."""
    world = generate_world(7, WorldConfig(num_frames=12))
    agent = _walkers(world)[0]
    spec = CameraSpec("side", 0.0, 0.0, 40.0, (0.0, 0.0, 0.9))
    K = camera_intrinsics(spec, 96, 96)
    c2w = pose_from_yaw(0.0, -4.0, 0.0, np.pi / 2) @ camera_to_ego(spec)  # looking at the origin along +y
    masks = []
    for phase in (0.0, np.pi / 2):
        agent.look["phase0"] = phase - 2 * np.pi * agent.traj["s"][0] / agent.look["stride"]
        draw = DrawList.build([(agent.local_mesh(0), 1)], world.lighting)
        _, _, inst, _ = render_view(world.layout, draw, K, c2w, 96, 96, 0, 0.0)
        masks.append(inst == 1)
    a, b = masks
    assert a.sum() > 100 and b.sum() > 100
    ya, xa = np.nonzero(a)
    yb, xb = np.nonzero(b)
    width_a, width_b = np.ptp(xa), np.ptp(xb)
    assert abs(width_a - width_b) >= 3  # legs apart vs together
    assert abs(int(a.sum()) - int(b.sum())) > 0 or not np.array_equal(a, b)
