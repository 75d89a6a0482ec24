"""Initialisation: voxel merging, normals, kNN scales, node layout, held-out frames never used."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from simsplat_core.scene import InitConfig, NonRigidNode, ObjectNode, RigidNode
from simsplat_core.scene.init import SHADOW_CATEGORIES, initial_graph, normal_map, quats_from_normals, voxel_merge
from simsplat_core.scene.knn import BRUTE_FORCE_MAX, knn_sq_distances
from simsplat_core.scene.transforms import quat_to_rotmat
from simsplat_core.types import CameraImage, SceneLog


def test_voxel_merge_averages_within_voxels_and_sizes() -> None:
    pts = np.array([[0.1, 0.1, 0.1], [0.3, 0.2, 0.1], [1.2, 0.1, 0.1], [0.1, 0.1, 0.1]])
    rgb = np.array([[1.0, 0, 0], [0.0, 0, 1], [0, 1, 0], [0.5, 0.5, 0.5]])
    size = np.array([0.5, 0.5, 0.5, 1.0])
    normals = np.array([[0, 0, 1.0], [0, 0, 1.0], [1.0, 0, 0], [0, 0, 0]])
    cloud = voxel_merge(pts, rgb, size, normals)
    assert cloud.points.shape == (3, 3)
    merged = np.flatnonzero(np.isclose(cloud.points[:, 0], 0.2))
    assert merged.size == 1
    k = merged[0]
    np.testing.assert_allclose(cloud.rgb[k], [0.5, 0.0, 0.5])
    np.testing.assert_allclose(cloud.normals[k], [0, 0, 1.0])
    assert cloud.size[k] == 0.5
    lone = np.flatnonzero(cloud.size == 1.0)[0]
    np.testing.assert_allclose(cloud.normals[lone], 0.0)  # unknown stays unknown


def test_quats_from_normals_rotate_z_onto_normal() -> None:
    rng = np.random.default_rng(0)
    n = rng.normal(size=(50, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n = np.concatenate([n, [[0, 0, -1.0], [0, 0, 1.0], [0, 0, 0]]])
    q = torch.as_tensor(quats_from_normals(n), dtype=torch.float64)
    z = quat_to_rotmat(q)[:, :, 2].numpy()
    np.testing.assert_allclose(z[:-1], n[:-1], atol=1e-9)
    np.testing.assert_allclose(q[-1].numpy(), [1, 0, 0, 0])


def test_normal_map_of_a_wall_faces_the_camera() -> None:
    width, height = 16, 12
    K = np.array([[10.0, 0, 8], [0, 10.0, 6], [0, 0, 1]])
    c2w = np.eye(4)
    depth = np.full((height, width), 5.0, dtype=np.float32)  # fronto-parallel wall at z = 5
    depth[:, :3] = np.inf
    img = CameraImage(0, 0, "cam", K, c2w, width, height, np.zeros((height, width, 3), np.float32), depth)
    normals = normal_map(img)
    np.testing.assert_allclose(normals[5, 8], [0, 0, -1.0], atol=1e-9)
    np.testing.assert_allclose(normals[5, 3], 0.0)  # next to the sky: unknown
    np.testing.assert_allclose(normals[0, 8], 0.0)  # border


@pytest.mark.parametrize("n", [200, BRUTE_FORCE_MAX + 3000])
def test_knn_distances(n: int) -> None:
    rng = np.random.default_rng(1)
    pts = rng.random((n, 3)).astype(np.float32) * 10
    d2 = knn_sq_distances(pts, 3)
    assert d2.shape == (n, 3) and bool(np.all(np.diff(d2, axis=1) >= -1e-6))
    t = torch.from_numpy(pts[:300])
    exact = torch.topk(torch.cdist(t, torch.from_numpy(pts)).square(), 4, largest=False).values[:, 1:].numpy()
    np.testing.assert_allclose(np.median(d2[:300] / np.maximum(exact, 1e-12)), 1.0, atol=1e-3)
    assert float(np.mean(np.isclose(d2[:300], exact, rtol=1e-3, atol=1e-6))) > 0.9


def test_node_layout(tiny_log: SceneLog) -> None:
    train = {img.frame_idx for img in tiny_log.images if img.split == "train"}
    graph = initial_graph(tiny_log, InitConfig(), train)
    objects = sorted(tiny_log.objects, key=lambda o: o.object_id)
    assert [n.node_id for n in graph.nodes] == list(range(len(objects) + 1))
    assert graph.nodes[0].node_type == "background"
    for node, obj in zip(graph.nodes[1:], objects):
        assert node.object_id == obj.object_id and node.category == obj.category
        assert node.node_type == obj.node_type
        assert isinstance(node, ObjectNode) and len(node.gaussians) > 0
        assert isinstance(node, NonRigidNode if obj.node_type == "nonrigid" else RigidNode)
        assert not (isinstance(node, NonRigidNode) and isinstance(node, RigidNode))
        track = tiny_log.track(obj.object_id)
        row = len(track) // 2
        f = int(track.frame_idx[row])
        center = track.center[0] if obj.node_type == "static" else track.center[row]
        np.testing.assert_allclose(node.poses[f, :3, 3].numpy(), center, atol=1e-4)
        if isinstance(node, NonRigidNode):
            assert set(node.deform_frames.tolist()) <= train
            assert node.offsets.shape == (len(node.gaussians), node.deform_frames.size, 3)
    bg = graph.nodes[0]
    dist = (bg.gaussians.means - torch.tensor(bg.center, dtype=torch.float32)).norm(dim=-1)
    assert int((dist > 0.9 * InitConfig().sky_radius).sum()) > 10  # the sky dome


def _poisoned(log: SceneLog) -> SceneLog:
    """Held-out images replaced by NaN pixels and depth: any use of them would show up as NaN."""
    images = []
    for img in log.images:
        if img.split == "test":
            nan = np.full_like(img.image, np.nan)
            img = dataclasses.replace(img, image=nan, depth=np.full_like(img.depth, np.nan))
        images.append(img)
    return dataclasses.replace(log, images=tuple(images))


def test_held_out_images_are_not_used(tiny_log: SceneLog) -> None:
    log = _poisoned(tiny_log)
    train = {img.frame_idx for img in log.images if img.split == "train"}
    graph = initial_graph(log, InitConfig(), train)
    for node in graph.nodes:
        for name, t in node.gaussians.named_tensors():
            assert bool(torch.isfinite(t).all()), (node.node_id, name)


def test_random_init_without_depth(tiny_log: SceneLog) -> None:
    images = tuple(dataclasses.replace(img, depth=None, instance=None) for img in tiny_log.images)
    log = dataclasses.replace(tiny_log, images=images)
    cfg = InitConfig(random_background_points=2000, random_object_points=50, shadow_spacing=0.0)
    train = {img.frame_idx for img in log.images if img.split == "train"}
    graph = initial_graph(log, cfg, train, seed=3)
    assert graph.metadata["init"] == "random"
    assert len(graph.nodes[0].gaussians) == 2000
    for node in graph.nodes[1:]:
        assert len(node.gaussians) == 50
        size = torch.as_tensor(tiny_log.track(node.object_id).size[0], dtype=torch.float32)
        assert bool((node.gaussians.means.abs() <= size / 2 + 1e-5).all())  # inside the box
    rgb = graph.nodes[0].gaussians.rgb
    assert float((rgb - 0.5).abs().max()) > 0.05  # coloured from the images, not all grey


def test_depth_without_instance_masks_assigns_points_by_box(tiny_log: SceneLog) -> None:
    """Lidar depth and 3D boxes but no instance masks (a DGP scene): an object's depth points initialise its
    node, not the background, so that removing the node removes the object."""
    images = tuple(dataclasses.replace(img, instance=None) for img in tiny_log.images)
    log = dataclasses.replace(tiny_log, images=images)
    cfg = InitConfig(shadow_spacing=0.0)
    train = {img.frame_idx for img in log.images if img.split == "train"}
    graph = initial_graph(log, cfg, train)
    assert graph.metadata["init"] == "depth"
    bg = graph.nodes[0].gaussians.means.double().numpy()
    seen = 0
    for node in graph.nodes[1:]:
        track = tiny_log.track(node.object_id)
        size = track.size[0]
        means = node.gaussians.means.double().numpy()
        if len(means) != cfg.random_object_points:  # initialised from depth: in the grown box
            seen += 1
            assert (np.abs(means) <= size / 2 + cfg.box_margin + 1e-6).all()
        for f in sorted(train & set(track.frame_idx.tolist())):
            to_local = np.linalg.inv(node.poses[f].double().numpy())
            local = bg @ to_local[:3, :3].T + to_local[:3, 3]
            deep = (np.abs(local) < size / 2 - 0.3).all(axis=1) & (local[:, 2] > -size[2] / 2 + 0.3)
            assert int(deep.sum()) == 0, (node.object_id, f)
    assert seen >= 2


def _shadow_rows(node: ObjectNode, size: np.ndarray, cfg: InitConfig) -> torch.Tensor:
    """Rows of a freshly initialised node that look like its shadow layer: black, ``shadow_opacity``, flat on
    the box's bottom plane."""
    g = node.gaussians
    on_floor = (g.means[:, 2] - (-0.5 * float(size[2]))).abs() < 0.05
    dark = g.rgb.amax(dim=-1) < 0.05
    faint = (torch.sigmoid(g.opacity_logits) - cfg.shadow_opacity).abs() < 1e-4
    return on_floor & dark & faint


def test_moving_objects_start_with_a_shadow_layer(tiny_log: SceneLog) -> None:
    """Vehicles and pedestrians get a grid of faint black discs over their footprint grown by the margin;
    other objects and the layer-less configuration get none."""
    cfg = InitConfig()
    train = {img.frame_idx for img in tiny_log.images if img.split == "train"}
    graph = initial_graph(tiny_log, cfg, train)
    without = {n.node_id: n for n in initial_graph(tiny_log, dataclasses.replace(cfg, shadow_spacing=0.0), train).nodes}
    checked = 0
    for node in graph.nodes[1:]:
        assert isinstance(node, ObjectNode)
        size = tiny_log.track(node.object_id).size[0]
        shadow = _shadow_rows(node, size, cfg)
        extra = len(node.gaussians) - len(without[node.node_id].gaussians)
        if node.category not in SHADOW_CATEGORIES:
            assert extra == 0 and int(shadow.sum()) == 0
            continue
        checked += 1
        assert int(shadow.sum()) == extra > 0
        xy = node.gaussians.means[shadow, :2].double().numpy()
        reach = size[:2] / 2 + cfg.shadow_margin
        np.testing.assert_allclose(np.abs(xy).max(axis=0), reach, atol=1e-5)  # the grid spans the grown footprint
        assert (np.diff(np.unique(xy[:, 0].round(6))) <= cfg.shadow_spacing + 1e-6).all()
    assert checked >= 2


def test_body_rows_leave_out_background_and_shadow_layers(tiny_log: SceneLog) -> None:
    """The object-coverage term counts an object's body, not its shadow layer nor the background."""
    from simsplat_core.scene.trainer import body_rows, box_bottoms

    cfg = InitConfig()
    train = {img.frame_idx for img in tiny_log.images if img.split == "train"}
    graph = initial_graph(tiny_log, cfg, train)
    body = body_rows(graph, box_bottoms(tiny_log), cfg.box_ground_clearance)
    offsets = graph.node_offsets()
    assert body.shape == (graph.num_gaussians,)
    start, stop = offsets[0]
    assert not bool(body[start:stop].any())
    for node in graph.nodes[1:]:
        assert isinstance(node, ObjectNode)
        start, stop = offsets[node.node_id]
        size = tiny_log.track(node.object_id).size[0]
        rows = body[start:stop]
        shadow = _shadow_rows(node, size, cfg)
        assert not bool(rows[shadow].any())
        high = node.gaussians.means[:, 2] > -0.5 * float(size[2]) + cfg.box_ground_clearance + 1e-4
        assert bool(rows[high].all())
