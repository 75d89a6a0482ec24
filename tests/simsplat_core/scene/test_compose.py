"""SceneGraph.at(t): rigid poses, non-rigid interpolation, presence, exclusion, purity."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from simsplat_core.scene.transforms import (
    interpolate_transforms,
    quat_multiply,
    quat_to_rotmat,
    rotmat_to_quat,
    se3_delta,
)

from .graphs import N_FRAMES, make_graph, rigid_track


def _yaw_quat(yaw: float) -> torch.Tensor:
    return torch.tensor([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def _block(composed, node_id: int) -> slice:
    for nid, start, stop in composed.node_slices:
        if nid == node_id:
            return slice(start, stop)
    raise KeyError(node_id)


@pytest.mark.parametrize("t", [0, 2, 3])
def test_rigid_node_lands_on_track(t: int) -> None:
    graph = make_graph()
    composed = graph.at(t)
    center, heading = rigid_track()
    rows = _block(composed, 1)
    means = composed.means[rows]
    # the Gaussian at the canonical origin sits on the track centre
    torch.testing.assert_close(means[0], torch.tensor(center[t], dtype=torch.float32), atol=1e-5, rtol=0)
    # a Gaussian 1 m ahead in the box frame sits 1 m along the heading
    ahead = torch.tensor([math.cos(heading[t]), math.sin(heading[t]), 0.0])
    torch.testing.assert_close(means[1] - means[0], ahead, atol=1e-5, rtol=0)
    # the heading rotates the quaternions: q_world = q_yaw ⊗ q_local
    local = torch.nn.functional.normalize(graph.node(1).gaussians.quats.detach(), dim=-1)
    expected = quat_multiply(_yaw_quat(float(heading[t])).expand_as(local), local)
    got = composed.quats[rows]
    sign = torch.sign((got * expected).sum(-1, keepdim=True))
    torch.testing.assert_close(got * sign, expected, atol=1e-5, rtol=0)
    # scales, colours and opacities are not moved
    torch.testing.assert_close(composed.scales[rows], graph.node(1).gaussians.scales.detach())
    torch.testing.assert_close(composed.colors[rows], graph.node(1).gaussians.rgb.detach())


def test_background_is_passed_through() -> None:
    graph = make_graph()
    composed = graph.at(1)
    rows = _block(composed, 0)
    bg = graph.node(0).gaussians
    torch.testing.assert_close(composed.means[rows], bg.means.detach())
    torch.testing.assert_close(composed.quats[rows], torch.nn.functional.normalize(bg.quats.detach(), dim=-1))


def test_fractional_time_interpolates_pose() -> None:
    graph = make_graph()
    center, heading = rigid_track()
    composed = graph.at(1.5)
    rows = _block(composed, 1)
    midpoint = torch.tensor(0.5 * (center[1] + center[2]), dtype=torch.float32)
    torch.testing.assert_close(composed.means[rows][0], midpoint, atol=1e-5, rtol=0)
    yaw = 0.5 * (heading[1] + heading[2])
    ahead = composed.means[rows][1] - composed.means[rows][0]
    assert math.atan2(float(ahead[1]), float(ahead[0])) == pytest.approx(yaw, abs=1e-5)


def test_nonrigid_offsets_interpolate_and_clamp() -> None:
    graph = make_graph()
    ped = graph.node(3)
    offsets = ped.offsets.detach()
    torch.testing.assert_close(ped.offsets_at(2.0), offsets[:, 1])
    torch.testing.assert_close(ped.offsets_at(3.0), 0.5 * (offsets[:, 1] + offsets[:, 2]))
    torch.testing.assert_close(ped.offsets_at(0.5), 0.75 * offsets[:, 0] + 0.25 * offsets[:, 1])
    torch.testing.assert_close(ped.offsets_at(-1.0), offsets[:, 0])
    torch.testing.assert_close(ped.offsets_at(9.0), offsets[:, 2])
    # composed: offsets are applied in the box frame before the pose
    pose = ped.poses[4]
    expected = (ped.gaussians.means.detach() + offsets[:, 2]) @ pose[:3, :3].T + pose[:3, 3]
    composed = graph.at(4)
    torch.testing.assert_close(composed.means[_block(composed, 3)], expected, atol=1e-5, rtol=0)


def test_holdout_offsets_interpolate_from_neighbours() -> None:
    graph = make_graph()
    ped = graph.node(3)
    offsets = ped.offsets.detach()
    # at stored frame 2 the held-out value is the interpolation of frames 0 and 4
    torch.testing.assert_close(ped.offsets_at(2.0, holdout=True), 0.5 * (offsets[:, 0] + offsets[:, 2]))
    # between stored frames nothing is held out
    torch.testing.assert_close(ped.offsets_at(3.0, holdout=True), ped.offsets_at(3.0))
    normal, held = graph.at(2), graph.at(2, holdout_offsets=True)
    rows = _block(normal, 3)
    assert not torch.allclose(normal.means[rows], held.means[rows])
    torch.testing.assert_close(normal.means[_block(normal, 1)], held.means[_block(held, 1)])


def test_presence_and_exclusion() -> None:
    graph = make_graph()
    assert graph.at(0).included_nodes == (0, 1, 2, 3)
    assert graph.at(1).included_nodes == (0, 1, 2)  # pedestrian absent at frame 1
    assert graph.at(0.5).included_nodes == (0, 1, 2)  # ... and so between frames 0 and 1
    assert graph.at(4).included_nodes == (0, 2, 3)  # car absent in the last frame
    composed = graph.at(2, exclude={1, 0})
    assert composed.included_nodes == (2, 3)
    assert set(composed.node_ids.tolist()) == {2, 3}
    assert composed.node_ids.dtype == torch.int32
    assert len(composed) == len(graph.node(2).gaussians) + len(graph.node(3).gaussians)
    assert len(graph.at(2, exclude={0, 1, 2, 3})) == 0
    # past the last frame the log nodes hold their last frame (the car stays absent): see test_graph_ops
    assert graph.at(N_FRAMES).included_nodes == graph.at(N_FRAMES - 1).included_nodes


def test_gaussian_ids_map_back_to_canonical_rows() -> None:
    graph = make_graph()
    composed = graph.at(2, exclude={2})
    offsets = graph.node_offsets()
    for nid, start, stop in composed.node_slices:
        lo, hi = offsets[nid]
        assert composed.gaussian_ids[start:stop].tolist() == list(range(lo, hi))


def test_at_has_no_hidden_state() -> None:
    graph = make_graph()
    first = graph.at(1.25)
    graph.at(3)
    graph.at(0, exclude={1})
    again = graph.at(1.25)
    for name in ("means", "quats", "scales", "opacities", "colors", "node_ids", "gaussian_ids"):
        assert torch.equal(getattr(first, name), getattr(again, name)), name


def test_at_is_differentiable_in_parameters_and_pose_refinement() -> None:
    graph = make_graph()
    car = graph.node(1)
    car.pose_deltas = torch.zeros((N_FRAMES, 6), requires_grad=True)
    for node in graph.nodes:
        node.gaussians.requires_grad_(True)
    composed = graph.at(2.5)
    (composed.means.square().sum() + composed.colors.sum()).backward()
    assert car.pose_deltas.grad is not None and float(car.pose_deltas.grad[2:4].abs().sum()) > 0
    assert float(car.pose_deltas.grad[[0, 1, 4]].abs().sum()) == 0.0
    # pedestrian at 2.5: between its deformation frames 2 and 4, frame 0 untouched
    grad = graph.node(3).offsets.grad
    assert float(grad[:, 1:].abs().sum()) > 0 and float(grad[:, 0].abs().sum()) == 0.0
    assert graph.node(0).gaussians.means.grad is not None


def test_transform_helpers_agree() -> None:
    g = torch.Generator().manual_seed(0)
    q = torch.nn.functional.normalize(torch.randn(64, 4, generator=g), dim=-1)
    q = torch.where(q[:, :1] < 0, -q, q)
    torch.testing.assert_close(rotmat_to_quat(quat_to_rotmat(q)), q, atol=1e-5, rtol=0)
    p = torch.nn.functional.normalize(torch.randn(64, 4, generator=g), dim=-1)
    torch.testing.assert_close(quat_to_rotmat(quat_multiply(p, q)), quat_to_rotmat(p) @ quat_to_rotmat(q),
                               atol=1e-5, rtol=0)
    delta = 0.1 * torch.randn(8, 6, generator=g)
    a = se3_delta(delta)
    b = se3_delta(-0.5 * delta)
    torch.testing.assert_close(interpolate_transforms(a, b, 0.0), a, atol=1e-5, rtol=0)
    torch.testing.assert_close(interpolate_transforms(a, b, 1.0), b, atol=1e-5, rtol=0)
    rot = a[:, :3, :3]
    torch.testing.assert_close(rot @ rot.transpose(1, 2), torch.eye(3).expand(8, 3, 3), atol=1e-5, rtol=0)
    assert np.allclose(se3_delta(torch.zeros(6)).numpy(), np.eye(4))
