"""``SceneGraph.at`` (batched over nodes) against a per-node reference composition, values and gradients,
and without host reads of device data."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torch import Tensor

from simsplat_core.scene import NonRigidNode, SceneGraph
from simsplat_core.scene.nodes import ObjectNode
from simsplat_core.scene.transforms import interpolate_transforms, quat_multiply, rotmat_to_quat, se3_delta
from tests.simsplat_core.scene.graphs import make_graph

HOST_READS = ("item", "tolist", "numpy", "cpu", "__bool__", "__float__", "__int__")


def reference_at(graph: SceneGraph, t: float, exclude: tuple[int, ...] = (),
                 holdout: bool = False) -> dict[int, tuple[Tensor, Tensor]]:
    """``node_id -> (world means [n, 3], world quats [n, 4])`` composed one node at a time."""
    ft = graph.resolve_time(t)
    out = {}
    for node in graph.nodes:
        if node.node_id in exclude:
            continue
        gs = node.gaussians
        quats = torch.nn.functional.normalize(gs.quats, dim=-1)
        if not isinstance(node, ObjectNode):
            out[node.node_id] = (gs.means, quats)
            continue
        if not bool(node.present[ft.i0] and node.present[ft.i1]):
            continue

        def pose_at(i: int, node: ObjectNode = node) -> Tensor:
            d = node.pose_deltas
            return node.poses[i] if d is None else node.poses[i] @ se3_delta(d[i])

        pose = pose_at(ft.i0) if ft.exact else interpolate_transforms(pose_at(ft.i0), pose_at(ft.i1), ft.w)
        means = gs.means
        if isinstance(node, NonRigidNode):
            means = means + node.offsets_at(float(t), holdout=holdout)
        out[node.node_id] = (means @ pose[:3, :3].T + pose[:3, 3],
                             quat_multiply(rotmat_to_quat(pose[:3, :3])[None], quats))
    return out


def learnable_graph() -> SceneGraph:
    graph = make_graph(features=2)
    for node in graph.object_nodes:
        node.pose_deltas = (0.05 * torch.randn((node.poses.shape[0], 6),
                                               generator=torch.Generator().manual_seed(node.node_id)))
    for node in graph.nodes:
        for tensor in node.tensors().values():
            tensor.requires_grad_(True)
    return graph


def grads(graph: SceneGraph, loss: Tensor) -> list[Tensor]:
    tensors = [t for n in graph.nodes for t in n.tensors().values()]
    got = torch.autograd.grad(loss, tensors, allow_unused=True)
    return [torch.zeros_like(t) if g is None else g for t, g in zip(tensors, got)]


@pytest.mark.parametrize("t", [0.0, 1.0, 2.0, 2.5, 3.25, 4.0, -1.0, 6.0])
@pytest.mark.parametrize(("exclude", "holdout"), [((), False), ((2,), True), ((0, 3), False)])
def test_batched_matches_per_node_reference(t: float, exclude: tuple[int, ...], holdout: bool) -> None:
    graph = learnable_graph()
    composed = graph.at(t, exclude=exclude, holdout_offsets=holdout)
    reference = reference_at(graph, t, exclude, holdout)
    assert composed.included_nodes == tuple(reference)
    weights = torch.linspace(0.5, 1.5, 7)
    loss_ref = torch.zeros(())
    for node_id, start, stop in composed.node_slices:
        means, quats = reference[node_id]
        torch.testing.assert_close(composed.means[start:stop], means, atol=1e-5, rtol=1e-5)
        torch.testing.assert_close(composed.quats[start:stop], quats, atol=1e-5, rtol=1e-5)
        assert torch.all(composed.node_ids[start:stop] == node_id)
        loss_ref = loss_ref + (torch.cat([means, quats], 1) * weights).sum()
    loss = (torch.cat([composed.means, composed.quats], 1) * weights).sum()
    for got, want in zip(grads(graph, loss), grads(graph, loss_ref)):
        torch.testing.assert_close(got, want, atol=1e-4, rtol=1e-4)


def test_at_reads_nothing_back_from_the_device(monkeypatch: pytest.MonkeyPatch) -> None:
    graph = learnable_graph()
    graph.at(0.0)  # the first call mirrors the presence masks on the host
    reads: list[str] = []
    for name in HOST_READS:
        original = getattr(torch.Tensor, name)

        def counted(self: Tensor, *args: object, _name: str = name, _fn: object = original, **kwargs: object) -> object:
            reads.append(_name)
            return _fn(self, *args, **kwargs)  # type: ignore[operator]

        monkeypatch.setattr(torch.Tensor, name, counted)
    for t in (1.0, 2.5, 4.0):
        composed = graph.at(t, holdout_offsets=True)
        (composed.means.sum() + composed.quats.sum()).backward()
    assert reads == []


def test_presence_mirror_belongs_to_each_derived_graph() -> None:
    graph = make_graph()
    assert 1 in graph.at(0.0).included_nodes
    moved = graph.with_poses(1, graph.node(1).poses, present=np.zeros(graph.frame_indices.size, dtype=bool))
    assert 1 not in moved.at(0.0).included_nodes
    assert 1 in graph.at(0.0).included_nodes
