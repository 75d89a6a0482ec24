"""SceneGraph.render: shapes, depth, and the per-pixel node id."""

from __future__ import annotations

import numpy as np
import torch

from simsplat_core.scene import BackgroundNode, GaussianSet, RigidNode, SceneGraph
from simsplat_core.scene.render import render_composed
from simsplat_core.scene.transforms import poses_from_boxes

from .graphs import camera, make_graph

W, H = 64, 48


def _wall_and_box() -> SceneGraph:
    """A background wall 20 m ahead (a grid of flat Gaussians) and one opaque object 6 m ahead."""
    ys, zs = np.meshgrid(np.linspace(-20, 20, 41), np.linspace(-14, 16, 31))
    wall = np.stack([np.full(ys.size, 20.0), ys.ravel(), zs.ravel()], axis=1)
    bg = GaussianSet.create(torch.tensor(wall, dtype=torch.float32), torch.full((ys.size,), 0.8),
                            torch.full((ys.size, 3), 0.3), 0.99)
    pts = np.stack(np.meshgrid(np.linspace(-0.5, 0.5, 5), np.linspace(-0.5, 0.5, 5), np.linspace(-0.5, 0.5, 5)),
                   -1).reshape(-1, 3)
    obj = GaussianSet.create(torch.tensor(pts, dtype=torch.float32), torch.full((pts.shape[0],), 0.2),
                             torch.tensor([[0.9, 0.1, 0.1]] * pts.shape[0]), 0.99)
    pose = torch.as_tensor(poses_from_boxes(np.array([[6.0, 0.0, 1.0]]), np.array([0.4])), dtype=torch.float32)
    return SceneGraph(frame_indices=np.array([0]), nodes=[
        BackgroundNode(0, bg, scale=10.0),
        RigidNode(1, obj, object_id="box", category="vehicle", poses=pose, present=torch.ones(1, dtype=torch.bool)),
    ])


def test_node_id_of_single_object_scene() -> None:
    graph = _wall_and_box()
    c2w, K = camera(W, H)
    with torch.no_grad():
        r = graph.render(0, c2w, K, W, H)
    assert r.rgb.shape == (1, H, W, 3) and r.alpha.shape == (1, H, W, 1) and r.depth.shape == (1, H, W, 1)
    assert r.node_id.shape == (1, H, W) and r.node_id.dtype == torch.int32
    # the image centre looks at the object, the corners at the wall
    cy, cx = H // 2, W // 2
    assert int(r.node_id[0, cy, cx]) == 1
    assert int(r.node_id[0, 2, 2]) == 0 and int(r.node_id[0, H - 3, W - 3]) == 0
    # object pixels are red and about 6 m away; wall pixels grey and about 20 m away
    obj = r.node_id[0] == 1
    wall = r.node_id[0] == 0
    assert int(obj.sum()) > 20 and int(wall.sum()) > 200
    assert float(r.rgb[0][obj][:, 0].mean()) > 0.6
    assert abs(float(r.depth[0, ..., 0][obj].median()) - 5.5) < 1.0
    assert abs(float(r.depth[0, ..., 0][wall].median()) - 20.0) < 1.0
    # excluding the object shows the wall behind it; nothing at all gives -1
    with torch.no_grad():
        no_obj = graph.render(0, c2w, K, W, H, exclude={1})
        nothing = graph.render(0, c2w, K, W, H, exclude={0, 1})
    assert int(no_obj.node_id[0, cy, cx]) == 0
    assert bool((nothing.node_id == -1).all()) and float(nothing.alpha.max()) == 0.0


def test_node_id_chunking_is_exact() -> None:
    graph = make_graph()
    c2w, K = camera(W, H)
    with torch.no_grad():
        composed = graph.at(2)
        one = render_composed(composed, c2w, K, W, H, id_chunk=1)
        many = render_composed(composed, c2w, K, W, H, id_chunk=32)
    assert torch.equal(one.node_id, many.node_id)
    assert set(torch.unique(many.node_id).tolist()) <= {-1, 0, 1, 2, 3}
    low = many.alpha[..., 0] < 0.5
    assert bool((many.node_id[low] == -1).all()) and bool((many.node_id[~low] >= 0).all())


def test_fused_node_ids_equal_the_separate_pass() -> None:
    graph = make_graph()
    c2w, K = camera(W, H)
    with torch.no_grad():
        for t in (0.0, 2.0, 3.5):
            composed = graph.at(t)
            separate = render_composed(composed, c2w, K, W, H)
            extra_t = torch.rand((len(composed), 2))
            fused = render_composed(composed, c2w, K, W, H, fused_ids=True, extra=extra_t)
            plain = render_composed(composed, c2w, K, W, H, with_node_ids=False, extra=extra_t)
            assert torch.equal(fused.node_id, separate.node_id)
            assert len(set(torch.unique(fused.node_id).tolist()) - {-1}) >= 2  # several nodes seen
            assert torch.allclose(fused.rgb, separate.rgb, atol=1e-6)
            assert torch.allclose(fused.extra, plain.extra, atol=1e-6)  # the caller's channels untouched


def test_render_without_node_ids_keeps_grad() -> None:
    graph = make_graph()
    for node in graph.nodes:
        node.gaussians.requires_grad_(True)
    c2w, K = camera(W, H)
    r = graph.render(2, c2w, K, W, H, with_node_ids=False)
    assert r.node_id is None and r.meta is not None
    r.rgb.sum().backward()
    assert graph.node(0).gaussians.colors.grad is not None
