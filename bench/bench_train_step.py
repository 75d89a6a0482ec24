"""Benchmark: scene-graph composition cost of one training step (``SceneGraph.at`` + a stub rasterizer).

    .venv/bin/python bench/bench_train_step.py [--reps 20] [--frames 40] [--vehicles 20] [--pedestrians 4]

A training step is compose -> rasterize -> loss -> backward. On a GPU the rasterizer is a small part of
it; the rest is Python and per-node tensor work in the composition. This bench isolates that part on
the CPU: the rasterizer is replaced by a stub (a weighted sum of every composed tensor, so every
parameter gets a gradient), and two compositions are compared side by side on the same graph:

* ``per_node``: a reference that composes node by node (one pose, one transform and one host read of
  the node's presence per node), the shape of a straightforward implementation;
* ``batched``: ``SceneGraph.at`` (all poses gathered at once, one batched transform, presence from a
  host mirror, ids built on the host).

Per variant: ``at`` forward ms, forward+backward ms (min and median over ``--reps``), the number of
torch operations dispatched in one forward+backward (``TorchDispatchMode``), and host reads (calls of
``Tensor.item / tolist / numpy / cpu / __bool__ / __float__ / __int__`` during one forward+backward:
each one is a device synchronisation on a GPU). Both variants must agree (checked before timing).

Writes ``bench/results/train_step.json``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import statistics
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import torch
from torch import Tensor
from torch.utils._python_dispatch import TorchDispatchMode

from simsplat_core.scene import BackgroundNode, GaussianSet, NonRigidNode, RigidNode, SceneGraph
from simsplat_core.scene.composed import ComposedGaussians
from simsplat_core.scene.nodes import OFFSETS, ObjectNode
from simsplat_core.scene.transforms import (
    interpolate_transforms,
    poses_from_boxes,
    quat_multiply,
    rotmat_to_quat,
    se3_delta,
)

logger = logging.getLogger("bench_train_step")
RESULTS = Path(__file__).parent / "results" / "train_step.json"
HOST_READS = ("item", "tolist", "numpy", "cpu", "__bool__", "__float__", "__int__")


class OpCounter(TorchDispatchMode):
    """Counts aten operations dispatched while active (forward and backward)."""

    def __init__(self) -> None:
        super().__init__()
        self.count = 0

    def __torch_dispatch__(self, func, types, args=(), kwargs=None):  # type: ignore[no-untyped-def]
        self.count += 1
        return func(*args, **(kwargs or {}))


@contextlib.contextmanager
def count_host_reads() -> Iterator[list[int]]:
    """Counts calls of the ``Tensor`` methods that read device data on the host."""
    counter = [0]
    originals = {name: getattr(torch.Tensor, name) for name in HOST_READS}

    def wrap(fn: Callable) -> Callable:
        def counted(self, *args, **kwargs):  # type: ignore[no-untyped-def]
            counter[0] += 1
            return fn(self, *args, **kwargs)
        return counted

    for name, fn in originals.items():
        setattr(torch.Tensor, name, wrap(fn))
    try:
        yield counter
    finally:
        for name, fn in originals.items():
            setattr(torch.Tensor, name, fn)


def make_graph(frames: int, vehicles: int, pedestrians: int, bg_gaussians: int, obj_gaussians: int,
               seed: int = 0) -> SceneGraph:
    """A driving-like graph: background, ``vehicles`` rigid nodes with learnable pose refinement (some
    absent in some frames), ``pedestrians`` non-rigid nodes with offsets every other frame."""
    g = torch.Generator().manual_seed(seed)
    rng = np.random.default_rng(seed)

    def gaussians(n: int) -> GaussianSet:
        gs = GaussianSet.create(torch.randn((n, 3), generator=g), torch.rand(n, generator=g) * 0.3 + 0.05,
                                torch.rand((n, 3), generator=g), 0.5, quats=torch.randn((n, 4), generator=g))
        for _name, tensor in gs.named_tensors():
            tensor.requires_grad_(True)
        return gs

    t = np.arange(frames, dtype=np.float64)
    nodes: list = [BackgroundNode(0, gaussians(bg_gaussians), scale=50.0)]
    for k in range(vehicles + pedestrians):
        center = np.stack([rng.uniform(-30, 30) + rng.uniform(-2, 2) * t, rng.uniform(-10, 10) + 0.3 * t,
                           np.full(frames, 0.8)], axis=1)
        poses = torch.as_tensor(poses_from_boxes(center, rng.uniform(-3, 3) + 0.05 * t), dtype=torch.float32)
        present = torch.as_tensor(rng.random(frames) > 0.1)
        deltas = (0.01 * torch.randn((frames, 6), generator=g)).requires_grad_(True)
        if k < vehicles:
            nodes.append(RigidNode(k + 1, gaussians(obj_gaussians), object_id=f"v{k}", category="vehicle",
                                   scale=2.5, poses=poses, present=present, pose_deltas=deltas))
        else:
            gs = gaussians(obj_gaussians // 4)
            deform = np.arange(0, frames, 2)
            gs.extras[OFFSETS] = (0.05 * torch.randn((len(gs), deform.size, 3), generator=g)).requires_grad_(True)
            nodes.append(NonRigidNode(k + 1, gs, object_id=f"p{k}", category="pedestrian", scale=1.0, poses=poses,
                                      present=present, pose_deltas=deltas, deform_frames=deform))
    return SceneGraph(frame_indices=np.arange(frames), nodes=nodes)


def per_node_at(graph: SceneGraph, t: float, holdout_offsets: bool = False) -> ComposedGaussians:
    """Reference composition, node by node (graph-axis times only; no own tracks, no ``exclude``)."""
    ft = graph.resolve_time(t)
    parts: list[tuple[int, Tensor, Tensor, GaussianSet]] = []
    offsets = graph.node_offsets()
    for node in graph.nodes:
        gs = node.gaussians
        quats = torch.nn.functional.normalize(gs.quats, dim=-1)
        if not isinstance(node, ObjectNode):
            parts.append((node.node_id, gs.means, quats, gs))
            continue
        if not bool(node.present[ft.i0] & node.present[ft.i1]):  # host read per node
            continue
        a = node.poses[ft.i0] @ se3_delta(node.pose_deltas[ft.i0]) if node.pose_deltas is not None \
            else node.poses[ft.i0]
        b = node.poses[ft.i1] @ se3_delta(node.pose_deltas[ft.i1]) if node.pose_deltas is not None \
            else node.poses[ft.i1]
        pose = a if ft.exact else interpolate_transforms(a, b, ft.w)
        means = gs.means
        if isinstance(node, NonRigidNode):
            means = means + node.offsets_at(float(t), holdout=holdout_offsets)
        world = means @ pose[:3, :3].T + pose[:3, 3]
        q = quat_multiply(rotmat_to_quat(pose[:3, :3])[None], quats)
        parts.append((node.node_id, world, q, gs))
    counts = [len(gs) for *_, gs in parts]
    starts = np.concatenate([[0], np.cumsum(counts)])
    return ComposedGaussians(
        t=float(t), means=torch.cat([p[1] for p in parts]), quats=torch.cat([p[2] for p in parts]),
        scales=torch.cat([p[3].scales for p in parts]), opacities=torch.cat([p[3].opacities for p in parts]),
        colors=torch.cat([p[3].rgb for p in parts]), features=None,
        node_ids=torch.cat([torch.full((c,), p[0], dtype=torch.int32) for p, c in zip(parts, counts)]),
        gaussian_ids=torch.cat([torch.arange(*offsets[p[0]]) for p in parts]),
        node_slices=tuple((p[0], int(starts[i]), int(starts[i + 1])) for i, p in enumerate(parts)))


def stub_rasterize(c: ComposedGaussians) -> Tensor:
    """A scalar that depends on every composed tensor (stands in for rasterize + loss)."""
    return (c.means.sum() + 0.5 * c.quats.sum() + c.scales.sum() + c.opacities.sum() + c.colors.sum())


def params(graph: SceneGraph) -> list[Tensor]:
    return [t for n in graph.nodes for t in n.tensors().values() if t.requires_grad]


def measure(compose: Callable[[float], ComposedGaussians], graph: SceneGraph, times: list[float],
            reps: int) -> dict[str, float]:
    """Forward / forward+backward wall times, dispatched ops and host reads of one composition."""
    def step(t: float, backward: bool) -> None:
        out = stub_rasterize(compose(t))
        if backward:
            out.backward()
            for p in params(graph):
                p.grad = None

    for t in times[:3]:
        step(t, True)  # warm-up (also fills host mirrors)
    fwd, fwd_bwd = [], []
    for r in range(reps):
        t = times[r % len(times)]
        with torch.no_grad():
            t0 = time.perf_counter()
            step(t, False)
            fwd.append((time.perf_counter() - t0) * 1e3)
        t0 = time.perf_counter()
        step(t, True)
        fwd_bwd.append((time.perf_counter() - t0) * 1e3)
    counter = OpCounter()
    with count_host_reads() as reads, counter:
        step(times[0], True)
    return {"at_forward_ms_min": min(fwd), "at_forward_ms_median": statistics.median(fwd),
            "forward_backward_ms_min": min(fwd_bwd), "forward_backward_ms_median": statistics.median(fwd_bwd),
            "torch_ops": counter.count, "host_reads": reads[0]}


def check_agree(graph: SceneGraph, t: float) -> float:
    """Largest absolute difference between the two compositions (values and gradients)."""
    worst = 0.0
    grads = []
    for compose in (lambda: per_node_at(graph, t), lambda: graph.at(t)):
        c = compose()
        stub_rasterize(c).backward()
        grads.append([None if p.grad is None else p.grad.clone() for p in params(graph)])
        for p in params(graph):
            p.grad = None
        grads[-1].append(torch.cat([c.means, c.quats, c.scales, c.colors], 1).detach())
    for a, b in zip(*grads):
        if a is None or b is None:  # a node absent at t: no gradient, or a zero one
            a, b = (b, a) if a is None else (a, b)
            worst = max(worst, 0.0 if a is None else float(a.abs().max()))
            continue
        worst = max(worst, float((a - b).abs().max()))
    return worst


def main() -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=20)
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--vehicles", type=int, default=20)
    parser.add_argument("--pedestrians", type=int, default=4)
    parser.add_argument("--bg-gaussians", type=int, default=20000)
    parser.add_argument("--obj-gaussians", type=int, default=1500)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    graph = make_graph(args.frames, args.vehicles, args.pedestrians, args.bg_gaussians, args.obj_gaussians)
    times = [float(f) for f in np.random.default_rng(1).permutation(args.frames)]
    max_diff = check_agree(graph, times[0])
    variants = {"per_node": lambda t: per_node_at(graph, t), "batched": lambda t: graph.at(t)}
    results = {name: measure(fn, graph, times, args.reps) for name, fn in variants.items()}
    for name, r in results.items():
        logger.info("%-9s at fwd %6.1f ms  fwd+bwd %6.1f ms  ops %5d  host reads %d", name,
                    r["at_forward_ms_median"], r["forward_backward_ms_median"], r["torch_ops"], r["host_reads"])
    out = {"config": {**vars(args), "num_gaussians": graph.num_gaussians, "device": "cpu",
                      "rasterizer": "stub (sum of composed tensors)", "torch": torch.__version__},
           "max_abs_difference": max_diff, "results": results,
           "speedup_forward_backward": results["per_node"]["forward_backward_ms_median"]
           / results["batched"]["forward_backward_ms_median"]}
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    tmp = RESULTS.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(out, indent=2) + "\n")
    tmp.replace(RESULTS)
    logger.info("wrote %s (max |difference| %.2e)", RESULTS, max_diff)


if __name__ == "__main__":
    main()
