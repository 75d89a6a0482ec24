"""A tiny end-to-end reconstruction: the loss drops and held-out frames beat a trivial baseline."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from simsplat_core.scene import (
    DensifyConfig,
    NonRigidNode,
    ReconstructionConfig,
    ReconstructionResult,
    SceneGraph,
    reconstruct,
)
from simsplat_core.scene.evaluate import render_views, summarise
from simsplat_core.scene.image_metrics import psnr
from simsplat_core.scene.init import initial_graph
from simsplat_core.scene.views import view_batches
from simsplat_core.types import SceneLog

ITERATIONS = 100


@pytest.fixture(scope="module")
def run(tiny_log: SceneLog) -> tuple[ReconstructionResult, list[tuple[int, int, dict[str, float]]]]:
    calls: list[tuple[int, int, dict[str, float]]] = []
    config = ReconstructionConfig(iterations=ITERATIONS, densify=DensifyConfig(refine_start=40, refine_every=30),
                                  eval_train_frames=2, seed=1)
    result = reconstruct(tiny_log, config, progress=lambda s, t, d: calls.append((s, t, dict(d))))
    return result, calls


def test_metrics_and_progress(run) -> None:
    result, calls = run
    for key in ("psnr_test", "ssim_test", "psnr_test_dynamic", "ssim_test_dynamic", "psnr_train", "iterations",
                "wall_time_s", "seconds_per_iteration", "num_gaussians", "num_nodes"):
        assert key in result.metrics, key
    assert result.metrics["iterations"] == ITERATIONS
    assert result.metrics["num_gaussians"] == result.graph.num_gaussians
    assert result.metrics["num_nodes"] == len(result.graph.nodes)
    assert calls[0][:2] == (1, ITERATIONS) and calls[-1][0] == ITERATIONS
    assert len(calls) >= ITERATIONS // 10
    assert {"loss", "psnr", "num_gaussians"} <= set(calls[0][2])


def test_loss_decreases(run) -> None:
    _, calls = run
    losses = [d["loss"] for _, _, d in calls]
    assert np.mean(losses[-3:]) < 0.8 * np.mean(losses[:2])


def test_held_out_frames_beat_trivial_baseline(run, tiny_log: SceneLog) -> None:
    result, _ = run
    renders = result.test_renders
    assert {(r.frame_idx, r.camera) for r in renders} == {
        (img.frame_idx, img.camera) for img in tiny_log.images if img.split == "test"}
    train_mean = np.mean([img.image.mean(axis=(0, 1)) for img in tiny_log.images if img.split == "train"], axis=0)
    baseline = []
    for r in renders:
        assert r.rgb.shape == r.gt_rgb.shape == (48, 64, 3) and r.rgb.dtype == np.float32
        assert r.alpha.shape == r.depth.shape == r.node_id.shape == r.dynamic_mask.shape == (48, 64)
        assert r.node_id.dtype == np.int32 and r.dynamic_mask.dtype == bool
        flat = np.broadcast_to(train_mean, r.gt_rgb.shape).astype(np.float32)
        baseline.append(float(psnr(torch.from_numpy(flat), torch.from_numpy(r.gt_rgb))))
    assert result.metrics["psnr_test"] > np.mean(baseline) + 3.0
    assert 0.0 < result.metrics["ssim_test"] <= 1.0


def test_training_improves_on_the_initialisation(run, tiny_log: SceneLog) -> None:
    result, _ = run
    train_frames = {img.frame_idx for img in tiny_log.images if img.split == "train"}
    init = initial_graph(tiny_log, ReconstructionConfig().init, train_frames, seed=1)
    init = init.with_eps2d(result.graph.eps2d)
    test = [b for b in view_batches(tiny_log) if b.split == "test"]
    before = summarise(render_views(init, test, tiny_log.objects, with_node_ids=False), "test")["psnr_test"]
    assert result.metrics["psnr_test"] > before + 0.5


def test_held_out_frames_are_not_trained(run, tiny_log: SceneLog) -> None:
    result, _ = run
    test_frames = {img.frame_idx for img in tiny_log.images if img.split == "test"}
    for node in result.graph.nodes:
        if isinstance(node, NonRigidNode):
            assert not set(node.deform_frames.tolist()) & test_frames


def test_result_graph_round_trips(run, tiny_log: SceneLog) -> None:
    result, _ = run
    img = next(i for i in tiny_log.images if i.split == "test")
    back = SceneGraph.from_records(result.graph.to_records(tiny_log.seq_id))
    c2w, K = img.cam_to_world[None], img.K[None]
    with torch.no_grad():
        a = result.graph.render(img.frame_idx, c2w, K, img.width, img.height)
        b = back.render(img.frame_idx, c2w, K, img.width, img.height)
    torch.testing.assert_close(b.rgb, a.rgb, atol=1e-5, rtol=0)
    assert torch.equal(a.node_id, b.node_id)
    assert math.isfinite(result.metrics["psnr_train"])
