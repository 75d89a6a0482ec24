"""The optimiser of a scene graph: one fused ``torch.optim.Adam`` over every node's tensors.

Tensors sharing a name and a learning rate share a param group (fewer groups = fewer fused-kernel
launches: ~40 instead of ~130 for the demo scene). Each group carries ``name`` and a ``node_ids`` list
parallel to ``params``, so densification can find and replace one node's rows (:func:`replace_rows`)
while keeping Adam's moments aligned. Learning rates come from ``LearningRates.for_type(node_type)``;
``means`` is scaled by the node's ``scale`` and decays exponentially (:func:`set_means_lr`).
"""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch import Tensor

from simsplat_core.scene.config import LearningRates
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.nodes import ObjectNode, SceneNode

#: Adam state entries that are per-row (the rest, e.g. ``step``, is copied as is).
ROW_STATE_KEYS: tuple[str, ...] = ("exp_avg", "exp_avg_sq")


def _lr(lrs: LearningRates, node: SceneNode, name: str) -> float:
    value = lrs.for_type(node.node_type).get(name)
    return value * node.scale if name == "means" else value


def make_trainable(graph: SceneGraph) -> None:
    """Turn every learnable tensor of the graph into a leaf that requires grad (in place)."""
    for node in graph.nodes:
        node.gaussians = node.gaussians.map_rows(lambda _, t: t.detach().requires_grad_(True))
        if isinstance(node, ObjectNode) and node.pose_deltas is not None:
            node.pose_deltas = node.pose_deltas.detach().requires_grad_(True)


def build_optimizer(graph: SceneGraph, lrs: LearningRates) -> torch.optim.Adam:
    """Fused Adam over all node tensors; groups ``{"params", "node_ids", "name", "lr", "base_lr"}``."""
    make_trainable(graph)
    groups: dict[tuple[str, float], dict] = {}
    for node in graph.nodes:
        for name, tensor in node.tensors().items():
            lr = _lr(lrs, node, name)
            group = groups.setdefault((name, lr), {"params": [], "node_ids": [], "name": name, "lr": lr,
                                                   "base_lr": lr})
            group["params"].append(tensor)
            group["node_ids"].append(node.node_id)
    return torch.optim.Adam(list(groups.values()), lr=1e-3, eps=1e-15, fused=True)


def set_means_lr(optimizer: torch.optim.Optimizer, step: int, total: int, final_factor: float) -> None:
    """Exponential decay of every ``means`` group: ``base_lr * final_factor ** (step / total)``."""
    factor = final_factor ** (min(step, total) / max(total, 1))
    for group in optimizer.param_groups:
        if group["name"] == "means":
            group["lr"] = group["base_lr"] * factor


def slots_of(optimizer: torch.optim.Optimizer, node_id: int) -> dict[str, tuple[dict, int]]:
    """``name -> (param group, position in its params)`` of one node's tensors."""
    out = {}
    for group in optimizer.param_groups:
        for pos, nid in enumerate(group["node_ids"]):
            if nid == node_id:
                out[group["name"]] = (group, pos)
    return out


def node_params(optimizer: torch.optim.Optimizer, node_id: int) -> dict[str, Tensor]:
    """``name -> tensor`` the optimizer holds for one node."""
    return {name: group["params"][pos] for name, (group, pos) in slots_of(optimizer, node_id).items()}


def replace_rows(
    node: SceneNode,
    optimizer: torch.optim.Optimizer,
    param_fn: Callable[[str, Tensor], Tensor],
    state_fn: Callable[[str, Tensor], Tensor],
) -> None:
    """Replace a node's Gaussian rows and keep Adam consistent.

    ``param_fn(name, tensor)`` returns the new rows of each row tensor (detached input);
    ``state_fn(name, moment)`` does the same for each Adam moment (``exp_avg``, ``exp_avg_sq``). The new
    tensors become leaves requiring grad, swapped into the node's param groups with their state.
    """
    slots = slots_of(optimizer, node.node_id)
    new_set = node.gaussians.map_rows(lambda name, t: param_fn(name, t.detach()).requires_grad_(True))
    for name, new in new_set.named_tensors():
        if name not in slots:
            continue
        group, pos = slots[name]
        old = group["params"][pos]
        state = optimizer.state.pop(old, None)
        group["params"][pos] = new
        if state:
            optimizer.state[new] = {k: (state_fn(name, v) if k in ROW_STATE_KEYS else v) for k, v in state.items()}
    node.gaussians = new_set


def zero_moments(optimizer: torch.optim.Optimizer, node_id: int, name: str) -> None:
    """Reset Adam's moments of one tensor (e.g. after an opacity reset)."""
    slot = slots_of(optimizer, node_id).get(name)
    if slot is None:
        return
    state = optimizer.state.get(slot[0]["params"][slot[1]])
    if state:
        for key in ROW_STATE_KEYS:
            if key in state:
                state[key].zero_()
