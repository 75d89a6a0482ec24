"""Speed profiles, paths and non-interpenetration of the placed agents."""

from __future__ import annotations

import numpy as np

from simsplat_core.scenario.geometry import footprints_overlap
from simsplat_core.world import WorldConfig, generate_world
from simsplat_core.world import behaviors as bh
from simsplat_core.world.agents import EGO_SIZE
from simsplat_core.world.road import RoadLayout


def test_speed_profile_stops_at_requested_point():
    layout = RoadLayout()
    motion = bh.stop_at_line(layout, "N", 0, speed=8.0, decel=2.5, t_brake=0.5, gap=1.0, length=4.6)
    t = np.linspace(0.0, 6.0, 601)
    s, v = motion.profile.sample(t)
    assert np.all(np.diff(s) >= -1e-12) and np.all(v >= 0.0)
    assert v[0] == 8.0 and v[-1] == 0.0
    np.testing.assert_allclose(s[-1], motion.path.marks["stop"] - 1.0 - 2.3, atol=1e-9)
    # speed is the derivative of arc length
    np.testing.assert_allclose(np.gradient(s, t)[5:-5], v[5:-5], atol=0.05)


def test_routes_turn_by_ninety_degrees():
    layout = RoadLayout()
    for turn, sign in (("left", 1.0), ("right", -1.0)):
        path = bh.drive(layout, "W", 0 if turn == "left" else 1, turn, 6.0, 0.0).path
        dh = np.rad2deg(path.heading(path.length) - path.heading(0.0))
        np.testing.assert_allclose(dh, sign * 90.0, atol=1.0)
    straight = bh.drive(layout, "W", 1, "straight", 8.0, 0.0).path
    assert np.ptp(straight.points[:, 1]) < 1e-9


def test_agents_do_not_interpenetrate():
    world = generate_world(4, WorldConfig(num_frames=40))
    ego_xy = world.ego_poses[:, :2, 3]
    ego_h = np.arctan2(world.ego_poses[:, 1, 0], world.ego_poses[:, 0, 0])
    agents = world.agents
    for i, a in enumerate(agents):
        assert not footprints_overlap(a.traj["xy"], a.traj["heading"], a.size[:2], ego_xy, ego_h, EGO_SIZE[:2]).any()
        for b in agents[i + 1 :]:
            assert not footprints_overlap(
                a.traj["xy"], a.traj["heading"], a.size[:2], b.traj["xy"], b.traj["heading"], b.size[:2]
            ).any(), (a.object_id, b.object_id)


def test_footprint_overlap_basic():
    c = np.zeros((1, 2))
    h = np.zeros(1)
    assert footprints_overlap(c, h, (4.0, 2.0), c + [3.9, 0.0], h, (4.0, 2.0))[0]
    assert not footprints_overlap(c, h, (4.0, 2.0), c + [4.1, 0.0], h, (4.0, 2.0))[0]
    assert footprints_overlap(c, h, (4.0, 2.0), c + [3.0, 2.0], h + np.pi / 4, (4.0, 2.0))[0]
