"""Assets as scene-graph nodes: rigid placement on a pose track, pedestrian gait retimed by arc length."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from simsplat_core.editing.assets.nodes import asset_node, gait_loop, path_arc_length, source_deform_times
from simsplat_core.editing.assets.procedural import procedural_asset
from simsplat_core.scene import NonRigidNode, RigidNode, SceneGraph
from simsplat_core.scene.pose_track import Extrapolation, PoseTrack
from simsplat_core.scene.transforms import poses_from_boxes
from tests.simsplat_core.editing.assets.fixtures import gait_offsets, mesh_vehicle, walking_pedestrian

GRAPH_FRAMES = np.arange(40)


def straight_track(speed_m_per_frame: float, frames: np.ndarray, z: float = 0.9, heading: float = 0.3
                   ) -> tuple[PoseTrack, np.ndarray]:
    """A track along ``heading`` at constant speed, and its arc length ``[T]``."""
    s = speed_m_per_frame * (frames - frames[0])
    center = np.stack([5 + s * math.cos(heading), -2 + s * math.sin(heading), np.full(frames.size, z)], axis=1)
    poses = torch.as_tensor(poses_from_boxes(center, np.full(frames.size, heading)), dtype=torch.float32)
    return PoseTrack(frames.astype(np.float64), poses), s


def _offsets(node: NonRigidNode, frames) -> np.ndarray:
    """``[F, N]`` x-offsets of the node at ``frames``."""
    return np.stack([node.offsets_at(float(f))[:, 0].numpy() for f in frames])


def test_gait_follows_the_distance_walked_twice_as_fast_cycles_twice_as_fast() -> None:
    ped = walking_pedestrian(step_m=0.1)  # the source: a 1 m gait cycle, 0.1 m per frame
    slow_track, slow_s = straight_track(0.1, GRAPH_FRAMES)
    fast_track, fast_s = straight_track(0.2, GRAPH_FRAMES)
    slow = asset_node(ped, node_id=1, object_id="a", track=slow_track, arc_length=slow_s, graph_frames=GRAPH_FRAMES)
    fast = asset_node(ped, node_id=1, object_id="b", track=fast_track, arc_length=fast_s, graph_frames=GRAPH_FRAMES)
    assert isinstance(slow, NonRigidNode) and isinstance(fast, NonRigidNode)
    f = np.arange(20)
    np.testing.assert_allclose(_offsets(fast, f), _offsets(slow, 2 * f), atol=1e-6)
    # and both show the source's gait at their own distance walked: 0.1 (i+1) sin(2 pi s)
    expected = gait_offsets(fast_s[:20], 6).numpy()[..., 0].T
    np.testing.assert_allclose(_offsets(fast, f), expected, atol=1e-5)
    assert np.abs(_offsets(fast, [0, 1, 2])).max() > 0.1  # it does move


def test_a_path_longer_than_the_source_walk_loops_without_a_jump() -> None:
    ped = walking_pedestrian(step_m=0.1, frames=40)  # walked 3.9 m; whole cycles end at 3.0 m (frame 30)
    loop = gait_loop(ped.offsets, ped.deform_frames, ped.deform_arc_length)
    assert loop == 30
    frames = np.arange(120)
    track, s = straight_track(0.1, frames)  # 11.9 m: nearly four loops
    node = asset_node(ped, node_id=1, object_id="a", track=track, arc_length=s, graph_frames=GRAPH_FRAMES)
    assert node.deform_frames[0] == 0 and node.deform_frames[-1] == 119
    got = _offsets(node, frames)
    np.testing.assert_allclose(got, gait_offsets(s, 6).numpy()[..., 0].T, atol=1e-5)
    np.testing.assert_allclose(got[95], got[5], atol=1e-5)
    source_step = np.abs(np.diff(ped.offsets[..., 0].numpy(), axis=1)).max()
    assert np.abs(np.diff(got, axis=0)).max() <= source_step + 1e-5  # no jump where the loop wraps


def test_a_source_that_stood_loops_in_time() -> None:
    ped = walking_pedestrian(frames=40, standing_period=8)  # did not walk; offsets repeat every 8 frames
    assert ped.walked_m == 0.0
    loop = gait_loop(ped.offsets, ped.deform_frames, ped.deform_arc_length)
    assert loop == 32
    taus = source_deform_times(ped.deform_frames, ped.deform_arc_length, loop, np.arange(10, 80), np.zeros(70))
    np.testing.assert_allclose(taus, np.mod(np.arange(70), 32))
    track, s = straight_track(0.14, GRAPH_FRAMES)
    node = asset_node(ped, node_id=1, object_id="a", track=track, arc_length=s, graph_frames=GRAPH_FRAMES)
    got = _offsets(node, [3, 11, 35])
    np.testing.assert_allclose(got[0], got[1], atol=1e-6)  # period 8 in time, whatever the speed
    np.testing.assert_allclose(got[2], ped.offsets[:, 3, 0].numpy(), atol=1e-6)  # 35 mod 32 = 3


def test_arc_length_defaults_to_the_track_positions() -> None:
    ped = walking_pedestrian()
    track, s = straight_track(0.17, GRAPH_FRAMES)
    np.testing.assert_allclose(path_arc_length(track), s, atol=1e-4)
    given = asset_node(ped, node_id=1, object_id="a", track=track, arc_length=s, graph_frames=GRAPH_FRAMES)
    measured = asset_node(ped, node_id=1, object_id="a", track=track, arc_length=None, graph_frames=GRAPH_FRAMES)
    torch.testing.assert_close(given.gaussians.extras["offsets"], measured.gaussians.extras["offsets"], atol=1e-4,
                               rtol=0)
    with pytest.raises(ValueError, match="arc_length must be"):
        asset_node(ped, node_id=1, object_id="a", track=track, arc_length=s[:-1], graph_frames=GRAPH_FRAMES)


def test_rigid_assets_ride_their_track_and_stand_on_the_ground() -> None:
    car = mesh_vehicle()
    track, s = straight_track(0.8, np.arange(10, 60), z=car.size[2] / 2)  # runs past the graph's last frame
    track = track.with_policy(before=Extrapolation.ABSENT)  # appears at frame 10
    node = asset_node(car, node_id=1, object_id="ins", track=track, arc_length=s, graph_frames=GRAPH_FRAMES)
    assert isinstance(node, RigidNode) and node.node_type == "rigid" and node.scale == pytest.approx(car.half_diagonal)
    assert not bool(node.present[:10].any()) and bool(node.present[10:].all())
    graph = SceneGraph(GRAPH_FRAMES, [node])
    for t in (20.0, 55.5):  # on the frame axis and past it (the node's own track)
        world = graph.at(t).means.numpy()
        pose, present = track.sample(t)
        assert present
        assert world[:, 2].min() == pytest.approx(0.0, abs=0.03)  # wheels on the road
        np.testing.assert_allclose(world.mean(axis=0)[:2], pose[:2, 3].numpy(), atol=0.3)
    cone = asset_node(procedural_asset("traffic cone"), node_id=0, object_id="c", track=track, arc_length=None,
                      graph_frames=GRAPH_FRAMES)
    assert isinstance(cone, RigidNode) and cone.node_type == "static"
    edited = graph.with_node(cone, poses=track)  # how an inserted asset enters a graph
    assert [n.node_id for n in edited.nodes] == [1, 2] and edited.node(2).object_id == "c"
    assert len(graph.nodes) == 1
