"""``reconstruct(log, config)``: fit a scene graph to a driving log and evaluate it on held-out frames.

Per step: pick the next training frame (a fresh random permutation per epoch), render its cameras
(``cameras_per_step``, a random subset when fewer than all), loss
``(1 - λ) L1 + λ D-SSIM`` (+ optional inverse-depth L1, + non-rigid offset smoothness / magnitude,
+ pose-refinement magnitude), Adam, then densification (:class:`DensifyStrategy`). Frames of split
``"test"`` never enter initialisation or training. At the end the test frames (and a few training
frames) are rendered and scored (:mod:`simsplat_core.scene.evaluate`).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import torch
from torch import Tensor

from simsplat_core.compute_threads import compute_threads_limited
from simsplat_core.scene.config import ReconstructionConfig
from simsplat_core.scene.densify import DensifyState, DensifyStrategy
from simsplat_core.scene.evaluate import TestFrameRender, render_views, summarise
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.init import initial_graph
from simsplat_core.scene.losses import dssim_loss, psnr_from_mse, valid_mean
from simsplat_core.scene.nodes import BACKGROUND_ID, NonRigidNode, ObjectNode, RigidNode
from simsplat_core.scene.optim import build_optimizer, set_means_lr
from simsplat_core.scene.render import SceneRender, render_composed
from simsplat_core.scene.views import ViewBatch, view_batches
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: ``progress(step, total, {"loss", "psnr", "num_gaussians"})``.
ProgressFn = Callable[[int, int, dict[str, float]], None]


@dataclass
class ReconstructionResult:
    """What ``reconstruct`` returns.

    Attributes:
        graph: the trained scene graph (on the training device, tensors detached).
        metrics: ``psnr_test``, ``ssim_test``, ``psnr_test_dynamic``, ``ssim_test_dynamic``, ``psnr_train``
            (and the other train figures), ``iterations``, ``wall_time_s``, ``seconds_per_iteration``,
            ``init_time_s``, ``train_time_s``, ``eval_time_s``, ``num_gaussians``, ``num_nodes``,
            ``final_loss``.
        test_renders: one entry per held-out (frame, camera).
    """

    graph: SceneGraph
    metrics: dict[str, float]
    test_renders: list[TestFrameRender] = field(default_factory=list)


def resolve_device(name: str) -> torch.device:
    """``"auto"`` -> CUDA when available, else CPU."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise ValueError("ReconstructionConfig.device is 'cuda' but CUDA is not available")
    return torch.device(name)


def regularisers(graph: SceneGraph, config: ReconstructionConfig) -> Tensor:
    """Non-rigid offset magnitude / velocity / acceleration and pose-refinement magnitude (a scalar).

    Offset terms are summed over frames and xyz and averaged over Gaussians (``LossWeights``)."""
    w = config.loss
    total = torch.zeros((), device=graph.device)
    for node in graph.object_nodes:
        if isinstance(node, NonRigidNode) and len(node.gaussians):
            off = node.offsets  # [N, T, 3]
            if w.deform_magnitude:
                total = total + w.deform_magnitude * off.square().sum((1, 2)).mean()
            if w.deform_smooth and off.shape[1] > 1:
                total = total + w.deform_smooth * (off[:, 1:] - off[:, :-1]).square().sum((1, 2)).mean()
            if w.deform_accel and off.shape[1] > 2:
                accel = off[:, 2:] - 2.0 * off[:, 1:-1] + off[:, :-2]
                total = total + w.deform_accel * accel.square().sum((1, 2)).mean()
        if isinstance(node, ObjectNode) and node.pose_deltas is not None and w.pose_delta:
            total = total + w.pose_delta * node.pose_deltas.square().sum(-1).mean()
    return total


def image_loss(render: SceneRender, batch: ViewBatch, config: ReconstructionConfig) -> tuple[Tensor, Tensor]:
    """``(loss, mse)`` of one rendered batch against its ground truth (see :class:`LossWeights`):
    weighted L1 + D-SSIM on colour, object-coverage L1 (``render.extra``) against ``instance > 0``,
    inverse-depth L1 where the ground-truth depth is finite; every term over ``batch.valid`` pixels only."""
    rgb, gt, instance, w, valid = render.rgb, batch.rgb, batch.instance, config.loss, batch.valid
    if gt is None:
        raise ValueError(f"image_loss: the view batch of frame {batch.frame_idx} has no pixels to compare with")
    lam = w.dssim
    err = (rgb - gt).abs()
    objects = None if instance is None else (instance > 0).to(err.dtype)  # [C, H, W]
    if w.object_weight > 1 and objects is not None:
        l1 = valid_mean(err * (1.0 + (w.object_weight - 1.0) * objects[..., None]), valid)
    else:
        l1 = valid_mean(err, valid)
    loss = (1.0 - lam) * l1 + (lam * dssim_loss(rgb, gt, valid) if lam > 0 else 0.0)
    if w.object_mask > 0 and objects is not None and render.extra is not None:
        loss = loss + w.object_mask * valid_mean((render.extra[..., 0] - objects).abs(), valid)
    if w.depth > 0 and batch.depth is not None:
        measured = torch.isfinite(batch.depth) & (batch.depth > 0)
        if valid is not None:
            measured = measured & valid
        if bool(measured.any()):
            inv_gt = 1.0 / batch.depth[measured]
            inv = 1.0 / render.depth[..., 0][measured].clamp(min=1e-3)
            loss = loss + w.depth * (inv - inv_gt).abs().mean()
    return loss, valid_mean((rgb.detach() - gt).square(), valid)


def box_bottoms(log: SceneLog) -> dict[str, float]:
    """``object_id -> z`` of the bottom of its box in the box frame (``-height / 2``)."""
    out = {}
    for obj in log.objects:
        track = log.track(obj.object_id)
        out[obj.object_id] = -0.5 * float(track.size[0][2]) if len(track) else -0.5
    return out


@torch.no_grad()
def body_rows(graph: SceneGraph, bottoms: dict[str, float], clearance: float) -> Tensor:
    """``[N] bool`` over the graph's canonical rows: Gaussians of object nodes that lie at least ``clearance``
    above their box's bottom (the object's body; below it is its shadow layer and the road it stands on)."""
    parts = []
    for node in graph.nodes:
        z = node.gaussians.means[:, 2]
        if node.node_id == BACKGROUND_ID:
            parts.append(torch.zeros_like(z, dtype=torch.bool))
        else:
            parts.append(z >= bottoms.get(node.object_id, -math.inf) + clearance)
    return torch.cat(parts)


def train_step(graph: SceneGraph, optimizer: torch.optim.Optimizer, strategy: DensifyStrategy, state: DensifyState,
               batch: ViewBatch, step: int, config: ReconstructionConfig, holdout: bool,
               bottoms: dict[str, float] | None) -> tuple[float, float]:
    """One optimisation step on one view batch: compose, render, loss, Adam, densification.

    ``bottoms`` (box bottoms per object, :func:`box_bottoms`) turns on the object-coverage term, which
    counts the bodies of object nodes (:func:`body_rows`); ``None`` leaves it off.
    Returns ``(loss, mse)`` of the step (the MSE of the colour render, for a running PSNR).
    """
    set_means_lr(optimizer, step, config.iterations, config.lr.means_final_factor)
    composed = graph.at(batch.frame_idx, holdout_offsets=holdout)
    extra = None
    if bottoms is not None:
        body = body_rows(graph, bottoms, config.init.box_ground_clearance)
        extra = body[composed.gaussian_ids.to(body.device)].to(composed.means.dtype)[:, None]
    render = render_composed(composed, batch.cam_to_world, batch.Ks, batch.width, batch.height,
                             with_node_ids=False, backend=config.backend, extra=extra, eps2d=graph.eps2d)
    loss, mse = image_loss(render, batch, config)
    loss = loss + regularisers(graph, config)
    info = {"meta": render.meta, "composed": composed}
    strategy.step_pre_backward(state, info)
    loss.backward()
    optimizer.step()
    optimizer.zero_grad(set_to_none=True)
    stats = strategy.step_post_backward(graph, optimizer, state, step, info)
    if stats:
        logger.debug("step %d: %s, %d Gaussians", step, stats, graph.num_gaussians)
    return float(loss.detach()), float(mse)


def _add_pose_refinement(graph: SceneGraph) -> None:
    """Zero learnable pose refinements on the moving object nodes of a graph the trainer owns (in place)."""
    for node in graph.object_nodes:
        if not (isinstance(node, RigidNode) and node.static):
            node.pose_deltas = torch.zeros((node.poses.shape[0], 6), device=node.poses.device)


def _evenly(items: list, count: int) -> list:
    if count <= 0 or not items:
        return []
    idx = np.unique(np.linspace(0, len(items) - 1, min(count, len(items))).round().astype(int))
    return [items[i] for i in idx]


def reconstruct(log: SceneLog, config: ReconstructionConfig, progress: ProgressFn | None = None
                ) -> ReconstructionResult:
    """Reconstruct ``log`` as a scene graph (see the module docstring). Deterministic for a given seed on
    the CPU (CUDA atomics may differ in the last bits). ``config.num_threads`` (when set) applies during
    the call only: the process's thread counts are restored on return."""
    with compute_threads_limited(config.num_threads or None):
        return _reconstruct(log, config, progress)


def _reconstruct(log: SceneLog, config: ReconstructionConfig, progress: ProgressFn | None) -> ReconstructionResult:
    t_start = time.perf_counter()
    device = resolve_device(config.device)
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    batches = [b.to(device) for b in view_batches(log)]
    train = [b for b in batches if b.split == "train" and b.rgb is not None]
    test = [b for b in batches if b.split == "test" and b.rgb is not None]
    if not train:
        raise ValueError(f"{log.seq_id}: no training images with pixels to reconstruct from")
    train_frames = {b.frame_idx for b in train}

    graph = initial_graph(log, config.init, train_frames, seed=config.seed, device=device).with_eps2d(config.eps2d)
    if config.refine_poses:
        _add_pose_refinement(graph)
    optimizer = build_optimizer(graph, config.lr)
    strategy = DensifyStrategy(config.densify, config.iterations, seed=config.seed)
    state = strategy.initialize_state(graph)
    t_init = time.perf_counter()
    logger.info("%s: initialised %d Gaussians in %d nodes (%.1fs); training %d iterations on %s",
                log.seq_id, graph.num_gaussians, len(graph.nodes), t_init - t_start, config.iterations, device)

    use_mask = config.loss.object_mask > 0 and all(b.instance is not None for b in train)
    bottoms = box_bottoms(log) if use_mask else None
    order: list[int] = []
    loss_value = math.nan
    for step in range(config.iterations):
        if not order:
            order = rng.permutation(len(train)).tolist()
        batch = train[order.pop()]
        if config.cameras_per_step < batch.num_cameras:
            batch = batch.subset(sorted(rng.choice(batch.num_cameras, config.cameras_per_step, replace=False).tolist()))
        holdout = bool(rng.random() < config.deform_holdout)
        loss_value, mse_value = train_step(graph, optimizer, strategy, state, batch, step, config, holdout, bottoms)
        report = {"loss": loss_value, "psnr": float(psnr_from_mse(mse_value)),
                  "num_gaussians": float(graph.num_gaussians)}
        if config.eval_every and (step + 1) % config.eval_every == 0 and test:
            scores = summarise(render_views(graph, test, log.objects, config.backend, with_node_ids=False), "test")
            report.update(psnr_test=scores["psnr_test"], psnr_test_dynamic=scores["psnr_test_dynamic"])
            logger.info("step %d: test PSNR %.2f dB (dynamic %.2f), %d Gaussians", step + 1, scores["psnr_test"],
                        scores["psnr_test_dynamic"], graph.num_gaussians)
        if progress is not None and (step % config.progress_every == 0 or step == config.iterations - 1
                                     or "psnr_test" in report):
            progress(step + 1, config.iterations, report)
    graph = graph.detached()  # no grad, no optimizer references; the trainer's own graph is left as it is
    t_train = time.perf_counter()

    test_renders = render_views(graph, test, log.objects, backend=config.backend)
    train_renders = render_views(graph, _evenly(train, config.eval_train_frames), log.objects,
                                 backend=config.backend, with_node_ids=False)
    t_end = time.perf_counter()
    metrics = {
        **summarise(test_renders, "test"),
        **summarise(train_renders, "train"),
        "iterations": float(config.iterations),
        "wall_time_s": t_end - t_start,
        "init_time_s": t_init - t_start,
        "train_time_s": t_train - t_init,
        "eval_time_s": t_end - t_train,
        "seconds_per_iteration": (t_train - t_init) / config.iterations,
        "num_gaussians": float(graph.num_gaussians),
        "num_nodes": float(len(graph.nodes)),
        "final_loss": loss_value,
    }
    logger.info("%s: test PSNR %.2f dB (dynamic %.2f), SSIM %.3f; %d Gaussians; %.1fs", log.seq_id,
                metrics["psnr_test"], metrics["psnr_test_dynamic"], metrics["ssim_test"], graph.num_gaussians,
                metrics["wall_time_s"])
    return ReconstructionResult(graph=graph, metrics=metrics, test_renders=test_renders)
