"""Adaptive density control as a strategy object (gsplat's ``DefaultStrategy``) over scene-graph nodes.

Each node's Gaussians live in the node's own ``GaussianSet`` and optimizer groups, so the statistics
are kept per *canonical row* (the concatenation of all nodes in node order, ``SceneGraph.node_offsets``)
and every operation is applied node by node:

* :func:`duplicate` appends copies of selected rows (zero Adam moments for the copies);
* :func:`split` replaces selected rows by two children sampled from the parent Gaussian, scales divided
  by ``split_factor`` (zero moments for the children);
* :func:`prune` drops rows (their moments go with them);
* :func:`reset_opacity` clamps opacities to a small value and zeroes their moments.

Rows that are not touched keep their values and moments exactly (tests check it).

Per step: ``step_pre_backward`` makes the render's ``means2d`` keep its gradient; ``step_post_backward``
accumulates the screen-space gradient norm of the visible Gaussians (gsplat's normalisation:
``grad * (W / 2, H / 2) * C``) and, every ``refine_every`` steps in the refinement window, grows
Gaussians whose mean gradient exceeds ``grad_threshold`` (clone when small, split when larger than
``grow_scale3d`` x the node's scale), prunes transparent and oversized ones, and resets the statistics.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import torch
from torch import Tensor

from simsplat_core.render.projection import quat_to_rotmat
from simsplat_core.scene.config import DensifyConfig
from simsplat_core.scene.gaussians import logit
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.nodes import BackgroundNode, SceneNode
from simsplat_core.scene.optim import replace_rows, zero_moments

logger = logging.getLogger(__name__)


# ---------------------------------------------------------------------------------------------- generic ops
def duplicate(node: SceneNode, optimizer: torch.optim.Optimizer, mask: Tensor) -> None:
    """Append a copy of every row where ``mask [N]`` is true; copies get zero Adam moments."""
    sel = torch.nonzero(mask, as_tuple=False)[:, 0]
    replace_rows(node, optimizer,
                 lambda _, t: torch.cat([t, t[sel]]),
                 lambda _, m: torch.cat([m, torch.zeros_like(m[sel])]))


def split(node: SceneNode, optimizer: torch.optim.Optimizer, mask: Tensor, factor: float = 1.6,
          generator: torch.Generator | None = None) -> None:
    """Replace every row where ``mask [N]`` is true by two children.

    Children means are ``mean + R diag(scale) eps`` (``eps ~ N(0, I)``), scales ``scale / factor``; the
    other tensors are copied. Unselected rows keep their order and come first; children get zero moments.
    """
    sel = torch.nonzero(mask, as_tuple=False)[:, 0]
    keep = ~mask
    g = node.gaussians
    scales = torch.exp(g.log_scales.detach()[sel])  # [S, 3]
    rot = quat_to_rotmat(g.quats.detach()[sel])  # [S, 3, 3]
    eps = torch.randn((2, sel.shape[0], 3), dtype=scales.dtype, generator=generator).to(scales.device)
    offsets = torch.einsum("sij,bsj->bsi", rot, scales[None] * eps)  # [2, S, 3]

    def children(name: str, t: Tensor) -> Tensor:
        rows = t[sel]
        if name == "means":
            return (rows[None] + offsets).reshape(-1, 3)
        if name == "log_scales":
            return (rows - math.log(factor)).repeat(2, 1)
        return rows.repeat((2,) + (1,) * (rows.dim() - 1))

    replace_rows(node, optimizer,
                 lambda name, t: torch.cat([t[keep], children(name, t)]),
                 lambda _, m: torch.cat([m[keep], torch.zeros_like(m[sel]).repeat((2,) + (1,) * (m.dim() - 1))]))


def prune(node: SceneNode, optimizer: torch.optim.Optimizer, mask: Tensor) -> None:
    """Drop every row where ``mask [N]`` is true (with its Adam moments)."""
    keep = ~mask
    replace_rows(node, optimizer, lambda _, t: t[keep], lambda _, m: m[keep])


def reset_opacity(node: SceneNode, optimizer: torch.optim.Optimizer, value: float) -> None:
    """Clamp opacities to at most ``value`` and zero their Adam moments."""
    with torch.no_grad():
        node.gaussians.opacity_logits.clamp_(max=float(logit(torch.tensor(value))))
    zero_moments(optimizer, node.node_id, "opacity_logits")


# ---------------------------------------------------------------------------------------------- strategy
@dataclass
class DensifyState:
    """Statistics over canonical rows: ``grad2d [N]`` summed gradient norms, ``count [N]`` visibilities."""

    grad2d: Tensor
    count: Tensor


class DensifyStrategy:
    """gsplat-style strategy (see the module docstring) for a scene graph trained ``iterations`` steps.

    ``info`` passed to the step functions is a dict with ``"meta"`` (the colour pass's ``RasterMeta``)
    and ``"composed"`` (the ``ComposedGaussians`` that was rendered).
    """

    def __init__(self, config: DensifyConfig, iterations: int, seed: int = 0) -> None:
        self.config = config
        self.iterations = iterations
        self.stop = int(config.refine_stop_fraction * iterations)
        self.generator = torch.Generator().manual_seed(seed)

    def initialize_state(self, graph: SceneGraph) -> DensifyState:
        n, device = graph.num_gaussians, graph.device
        return DensifyState(torch.zeros(n, device=device), torch.zeros(n, device=device))

    def step_pre_backward(self, state: DensifyState, info: dict[str, Any]) -> None:
        if self.config.enabled:
            info["meta"].means2d.retain_grad()

    def step_post_backward(self, params: SceneGraph, optimizers: torch.optim.Optimizer, state: DensifyState,
                           step: int, info: dict[str, Any]) -> dict[str, int]:
        """Accumulate statistics; refine / reset when due. Returns counts of what it did (may be empty)."""
        cfg = self.config
        if not cfg.enabled or step >= self.stop:
            return {}
        self._accumulate(state, info)
        stats: dict[str, int] = {}
        if step >= cfg.refine_start and step % cfg.refine_every == 0 and step > 0:
            stats = self.refine(params, optimizers, state)
            fresh = self.initialize_state(params)
            state.grad2d, state.count = fresh.grad2d, fresh.count
        if cfg.reset_every and step > 0 and step % cfg.reset_every == 0:
            for node in params.nodes:
                reset_opacity(node, optimizers, 2.0 * cfg.prune_opacity)
            stats["reset"] = 1
        return stats

    @torch.no_grad()
    def _accumulate(self, state: DensifyState, info: dict[str, Any]) -> None:
        meta, composed = info["meta"], info["composed"]
        grad = meta.means2d.grad  # [C, N, 2]
        if grad is None:
            return
        scale = torch.tensor([meta.width / 2.0 * meta.n_cameras, meta.height / 2.0 * meta.n_cameras],
                             dtype=grad.dtype, device=grad.device)
        norms = (grad * scale).norm(dim=-1)  # [C, N]
        visible = meta.radii > 0  # [C, N]
        ids = composed.gaussian_ids.to(state.grad2d.device)
        state.grad2d.index_add_(0, ids, (norms * visible).sum(dim=0).to(state.grad2d.dtype))
        state.count.index_add_(0, ids, visible.sum(dim=0).to(state.count.dtype))

    @torch.no_grad()
    def refine(self, graph: SceneGraph, optimizer: torch.optim.Optimizer, state: DensifyState) -> dict[str, int]:
        """Grow (clone / split) and prune every node; returns the counts."""
        cfg = self.config
        offsets = graph.node_offsets()
        avg_all = state.grad2d / state.count.clamp(min=1)  # [N] over canonical rows
        grow_all = avg_all > cfg.grad_threshold
        budget = max(cfg.max_gaussians - graph.num_gaussians, 0)
        if int(grow_all.sum()) > budget:  # the largest gradients of the whole scene within the budget
            top = torch.topk(torch.where(grow_all, avg_all, torch.zeros_like(avg_all)), budget).indices
            grow_all = torch.zeros_like(grow_all)
            grow_all[top] = True
        totals = {"duplicated": 0, "split": 0, "pruned": 0}
        for node in graph.nodes:
            start, stop = offsets[node.node_id]
            if stop == start:
                continue
            grow = grow_all[start:stop]
            max_scale = torch.exp(node.gaussians.log_scales).amax(dim=-1)
            small = max_scale <= cfg.grow_scale3d * node.scale
            n_dup, n_split = int((grow & small).sum()), int((grow & ~small).sum())
            if n_dup:
                duplicate(node, optimizer, grow & small)
            if n_split:
                pad = torch.zeros(n_dup, dtype=torch.bool, device=grow.device)
                split(node, optimizer, torch.cat([grow & ~small, pad]), cfg.split_factor, self.generator)
            dead = self._prune_mask(node)
            n_pruned = int(dead.sum())
            if n_pruned:
                prune(node, optimizer, dead)
            totals["duplicated"] += n_dup
            totals["split"] += n_split
            totals["pruned"] += n_pruned
        logger.debug("refine: %s -> %d Gaussians", totals, graph.num_gaussians)
        return totals

    def _prune_mask(self, node: SceneNode) -> Tensor:
        """Transparent Gaussians, and Gaussians larger than ``prune_scale3d * max(scale, distance)``."""
        g = node.gaussians
        transparent = torch.sigmoid(g.opacity_logits) < self.config.prune_opacity
        center = torch.tensor(node.center if isinstance(node, BackgroundNode) else (0.0, 0.0, 0.0),
                              dtype=g.means.dtype, device=g.means.device)
        reach = (g.means - center).norm(dim=-1).clamp(min=node.scale)
        too_big = torch.exp(g.log_scales).amax(dim=-1) > self.config.prune_scale3d * reach
        return transparent | too_big
