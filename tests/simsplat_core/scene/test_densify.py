"""Densification ops keep Adam's state aligned with the rows; the strategy grows and prunes."""

from __future__ import annotations

import torch

from simsplat_core.scene import DensifyConfig, DensifyStrategy, LearningRates
from simsplat_core.scene.densify import duplicate, prune, reset_opacity, split
from simsplat_core.scene.optim import build_optimizer, node_params
from simsplat_core.scene.render import render_composed

from .graphs import camera, make_graph


def _trained_graph():
    """The unit graph after two Adam steps (so every row has non-zero moments)."""
    graph = make_graph(features=2)
    opt = build_optimizer(graph, LearningRates())
    c2w, K = camera()
    for t in (0, 2):
        composed = graph.at(t)
        r = render_composed(composed, c2w, K, 64, 48, with_node_ids=False)
        # a small term on every tensor so that every row of every node has Adam moments
        loss = r.rgb.square().mean() + 1e-3 * sum(t.square().sum() for n in graph.nodes
                                                  for _, t in n.gaussians.named_tensors())
        loss.backward()
        opt.step()
        opt.zero_grad()
    return graph, opt


def _snapshot(node, opt):
    out = {}
    for name, p in node_params(opt, node.node_id).items():
        if name == "pose_deltas":
            continue
        state = opt.state[p]
        out[name] = (p.detach().clone(), state["exp_avg"].clone(), state["exp_avg_sq"].clone())
    return out


def _check_consistent(node, opt) -> None:
    n = len(node.gaussians)
    tensors = dict(node.gaussians.named_tensors())
    for name, p in node_params(opt, node.node_id).items():
        assert p is tensors[name], name  # the optimizer holds the node's current tensors
        assert p.shape[0] == n and p.requires_grad and p.is_leaf
        state = opt.state[p]
        assert state["exp_avg"].shape == p.shape and state["exp_avg_sq"].shape == p.shape


def test_duplicate_keeps_rows_and_zeroes_new_moments() -> None:
    graph, opt = _trained_graph()
    node = graph.node(3)  # the pedestrian: has per-frame offsets in its extras
    before = _snapshot(node, opt)
    n = len(node.gaussians)
    mask = torch.tensor([True, False, True])
    duplicate(node, opt, mask)
    _check_consistent(node, opt)
    assert len(node.gaussians) == n + 2
    after = _snapshot(node, opt)
    for name, (value, m1, m2) in before.items():
        torch.testing.assert_close(after[name][0][:n], value)  # untouched rows keep their values ...
        torch.testing.assert_close(after[name][1][:n], m1)  # ... and their moments
        torch.testing.assert_close(after[name][2][:n], m2)
        torch.testing.assert_close(after[name][0][n:], value[mask])  # copies
        assert float(after[name][1][n:].abs().sum()) == 0.0 and float(after[name][2][n:].abs().sum()) == 0.0
    assert node.offsets.shape[0] == n + 2


def test_split_replaces_parents_by_two_smaller_children() -> None:
    graph, opt = _trained_graph()
    node = graph.node(0)
    before = _snapshot(node, opt)
    mask = torch.tensor([False, True, False])
    split(node, opt, mask, factor=1.6)
    _check_consistent(node, opt)
    assert len(node.gaussians) == 4
    after = _snapshot(node, opt)
    keep = ~mask
    for name, (value, m1, _) in before.items():
        torch.testing.assert_close(after[name][0][:2], value[keep])
        torch.testing.assert_close(after[name][1][:2], m1[keep])
        assert float(after[name][1][2:].abs().sum()) == 0.0
    parent_log_scale = before["log_scales"][0][1]
    expected = (parent_log_scale - torch.log(torch.tensor(1.6))).expand(2, 3)
    torch.testing.assert_close(after["log_scales"][0][2:], expected)
    # children stay within a few parent sigmas of the parent
    parent_mean = before["means"][0][1]
    assert float((after["means"][0][2:] - parent_mean).norm(dim=-1).max()) < 5 * float(parent_log_scale.exp().max())
    torch.testing.assert_close(after["colors"][0][2:], before["colors"][0][1].expand(2, 3))


def test_prune_and_reset_opacity() -> None:
    graph, opt = _trained_graph()
    node = graph.node(1)
    before = _snapshot(node, opt)
    mask = torch.tensor([True, False, False])
    prune(node, opt, mask)
    _check_consistent(node, opt)
    after = _snapshot(node, opt)
    for name, (value, _m1, m2) in before.items():
        torch.testing.assert_close(after[name][0], value[~mask])
        torch.testing.assert_close(after[name][2], m2[~mask])
    reset_opacity(node, opt, 0.01)
    _check_consistent(node, opt)
    assert float(torch.sigmoid(node.gaussians.opacity_logits.detach()).max()) <= 0.01 + 1e-6
    state = opt.state[node_params(opt, 1)["opacity_logits"]]
    assert float(state["exp_avg"].abs().sum()) == 0.0


def test_optimizer_still_steps_after_ops() -> None:
    graph, opt = _trained_graph()
    duplicate(graph.node(0), opt, torch.tensor([True, True, False]))
    split(graph.node(3), opt, torch.tensor([False, True, True]))
    prune(graph.node(2), opt, torch.tensor([True, False]))
    c2w, K = camera()
    composed = graph.at(2)
    r = render_composed(composed, c2w, K, 64, 48, with_node_ids=False)
    r.rgb.mean().backward()
    opt.step()
    for node in graph.nodes:
        _check_consistent(node, opt)


def test_strategy_grows_high_gradient_gaussians_and_prunes_transparent_ones() -> None:
    graph, opt = _trained_graph()
    cfg = DensifyConfig(refine_start=0, refine_every=1, grad_threshold=1e-4, grow_scale3d=0.05)
    strategy = DensifyStrategy(cfg, iterations=10)
    state = strategy.initialize_state(graph)
    offsets = graph.node_offsets()
    # pretend every Gaussian of the car was seen with a large gradient; make a background one transparent
    start, stop = offsets[1]
    state.grad2d[start:stop] = 1.0
    state.count[start:stop] = 1.0
    with torch.no_grad():
        graph.node(0).gaussians.opacity_logits[0] = -10.0
    n_car, n_bg = len(graph.node(1).gaussians), len(graph.node(0).gaussians)
    stats = strategy.refine(graph, opt, state)
    assert stats["duplicated"] + stats["split"] == n_car and stats["pruned"] >= 1
    assert len(graph.node(1).gaussians) == 2 * n_car
    assert len(graph.node(0).gaussians) == n_bg - 1
    for node in graph.nodes:
        _check_consistent(node, opt)


def test_strategy_accumulates_screen_gradients() -> None:
    graph, opt = _trained_graph()
    strategy = DensifyStrategy(DensifyConfig(refine_start=1000), iterations=10)
    state = strategy.initialize_state(graph)
    c2w, K = camera()
    composed = graph.at(2)
    r = render_composed(composed, c2w, K, 64, 48, with_node_ids=False)
    info = {"meta": r.meta, "composed": composed}
    strategy.step_pre_backward(state, info)
    r.rgb.square().mean().backward()
    assert strategy.step_post_backward(graph, opt, state, step=1, info=info) == {}
    visible = (r.meta.radii > 0).any(dim=0)
    ids = composed.gaussian_ids[visible]
    assert bool((state.count[ids] > 0).all()) and float(state.grad2d[ids].sum()) > 0
    hidden = torch.ones(graph.num_gaussians, dtype=torch.bool)
    hidden[composed.gaussian_ids] = False
    assert float(state.count[hidden].sum()) == 0.0  # absent nodes collect nothing
