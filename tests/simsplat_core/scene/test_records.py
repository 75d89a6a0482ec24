"""SceneRecords: plain-data columns and an exact render round trip."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from simsplat_core.scene import SceneGraph, SceneRecords

from .graphs import N_FRAMES, camera, make_graph


def _all_numpy_or_python(value) -> bool:
    if isinstance(value, torch.Tensor):
        return False
    if isinstance(value, dict):
        return all(_all_numpy_or_python(k) and _all_numpy_or_python(v) for k, v in value.items())
    if isinstance(value, (list, tuple)):
        return all(_all_numpy_or_python(v) for v in value)
    return True


def test_record_columns() -> None:
    graph = make_graph(features=4)
    rec = graph.to_records("scene-x")
    assert isinstance(rec, SceneRecords) and rec.scene_id == "scene-x"
    assert _all_numpy_or_python(vars(rec))
    n = graph.num_gaussians
    g = rec.gaussians
    assert g["node_id"].dtype == np.int32 and g["node_id"].shape == (n,)
    for name, width in (("mean", 3), ("log_scale", 3), ("quat", 4), ("color", 3), ("feature", 4)):
        assert g[name].dtype == np.float32 and g[name].shape == (n, width), name
    assert g["opacity_logit"].shape == (n,)
    assert g["color"].min() >= 0.0 and g["color"].max() <= 1.0
    assert [d["node_id"] for d in rec.nodes] == [0, 1, 2, 3]
    assert [d["node_type"] for d in rec.nodes] == ["background", "rigid", "static", "nonrigid"]
    assert rec.nodes[0]["object_id"] == "" and rec.nodes[1]["object_id"] == "car"
    poses = rec.node_poses
    assert poses["node_id"].dtype == np.int32 and poses["frame_idx"].dtype == np.int64
    assert poses["transform"].dtype == np.float32 and poses["transform"].shape[1] == 16
    # background: identity at every frame; car: absent in the last frame; pedestrian: absent at frame 1
    counts = {nid: int((poses["node_id"] == nid).sum()) for nid in range(4)}
    assert counts == {0: N_FRAMES, 1: N_FRAMES - 1, 2: N_FRAMES, 3: N_FRAMES - 1}
    bg = poses["transform"][poses["node_id"] == 0]
    np.testing.assert_array_equal(bg, np.tile(np.eye(4, dtype=np.float32).reshape(1, 16), (N_FRAMES, 1)))
    car = poses["transform"][(poses["node_id"] == 1) & (poses["frame_idx"] == 2)].reshape(4, 4)
    np.testing.assert_allclose(car, graph.node(1).poses[2].numpy(), atol=0)
    assert set(rec.deformations) == {3}
    assert rec.deformations[3].shape == (3, 3, 3) and rec.deformations[3].dtype == np.float32
    np.testing.assert_array_equal(rec.deformation_frames[3], [0, 2, 4])
    np.testing.assert_allclose(rec.deformations[3][1, :, 0], 0.2)


@pytest.mark.parametrize("t", [0.0, 2.0, 2.5, 3.0])
def test_round_trip_renders_identically(t: float) -> None:
    graph = make_graph(features=2)
    graph = graph.with_eps2d(0.1)  # the render low-pass is part of the model and travels in the metadata
    graph.node(1).pose_deltas = torch.full((N_FRAMES, 6), 0.01)  # refinement gets baked into the poses
    back = SceneGraph.from_records(graph.to_records("rt"))
    assert [n.node_type for n in back.nodes] == [n.node_type for n in graph.nodes]
    assert back.eps2d == 0.1 and back.metadata == graph.metadata
    c2w, K = camera()
    with torch.no_grad():
        a = graph.render(t, c2w, K, 64, 48)
        b = back.render(t, c2w, K, 64, 48)
    assert float(a.alpha.max()) > 0.3  # something is actually rendered
    torch.testing.assert_close(b.rgb, a.rgb, atol=1e-5, rtol=0)
    torch.testing.assert_close(b.alpha, a.alpha, atol=1e-5, rtol=0)
    torch.testing.assert_close(b.depth, a.depth, atol=1e-4, rtol=0)
    assert torch.equal(b.node_id, a.node_id)
    ca, cb = graph.at(t), back.at(t)
    torch.testing.assert_close(cb.means, ca.means.detach(), atol=1e-5, rtol=0)
    torch.testing.assert_close(cb.features, ca.features.detach())


def test_records_validation_names_the_problem() -> None:
    rec = make_graph().to_records("bad")
    rec.gaussians["quat"] = rec.gaussians["quat"][:, :3]
    with pytest.raises(ValueError, match="quat"):
        rec.validate()
    rec = make_graph().to_records("bad")
    rec.deformations[3] = rec.deformations[3][:, :2]
    with pytest.raises(ValueError, match="deformations"):
        SceneGraph.from_records(rec)
