"""Device check: the gsplat backend against the reference rasterizer, and the training loop's speed, in one run.

    .venv/bin/python bench/device_check.py [--cpu] [--tiny] [--out bench/results/device_check.json]

On a CUDA machine (the default) the fast backend is ``gsplat``; with ``--cpu`` it is this package's CPU
backend, so the same script runs (and is tested) without a GPU. Steps, each recorded in the JSON:

1. ``agreement``: a random scene rendered by the fast backend and by the dense reference (on the same
   device): largest differences of the colours, alphas, expected depth (pixels with ``alpha >= ED_EPS``)
   and the gradients of every Gaussian parameter of a weighted sum of the outputs;
2. ``rasterizer``: forward+backward time of the fast backend (median ms, synchronised);
3. ``train_step``: ``SceneGraph.at`` + render + loss + backward on a reconstructed scene (median ms);
4. ``reconstruct``: the default sequence (``generate_log(0, WorldConfig())``) reconstructed with the
   default configuration (``--tiny``: a small world and a few iterations), wall seconds and metrics.

Writes the JSON atomically (``--out``).
"""

from __future__ import annotations

import argparse
import json
import logging
import statistics
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import torch
from torch import Tensor

from simsplat_core.render.api import rasterization
from simsplat_core.render.types import ED_EPS
from simsplat_core.scene.config import ReconstructionConfig
from simsplat_core.scene.render import render_composed
from simsplat_core.scene.trainer import reconstruct
from simsplat_core.scene.views import view_batches
from simsplat_core.world import WorldConfig, generate_log

logger = logging.getLogger("device_check")
DEFAULT_OUT = Path(__file__).parent / "results" / "device_check.json"


def random_scene(n: int, width: int, height: int, device: torch.device, seed: int = 0) -> tuple:
    """Rasterizer arguments of ``n`` Gaussians in front of one OpenCV camera at the origin."""
    g = torch.Generator().manual_seed(seed)
    means = torch.cat([torch.rand((n, 2), generator=g) * 4 - 2, torch.rand((n, 1), generator=g) * 8 + 2], 1)
    quats = torch.randn((n, 4), generator=g)
    scales = torch.rand((n, 3), generator=g) * 0.2 + 0.02
    opacities = torch.rand(n, generator=g) * 0.9 + 0.05
    colors = torch.rand((n, 3), generator=g)
    K = torch.tensor([[0.8 * width, 0.0, width / 2], [0.0, 0.8 * width, height / 2], [0.0, 0.0, 1.0]])
    tensors = [t.to(device).requires_grad_(True) for t in (means, quats, scales, opacities, colors)]
    return (*tensors, torch.eye(4, device=device)[None], K.to(device)[None], width, height)


def _sync(device: torch.device) -> None:
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def _median_ms(fn: Callable[[], object], device: torch.device, reps: int) -> float:
    fn()
    times = []
    for _ in range(reps):
        _sync(device)
        t0 = time.perf_counter()
        fn()
        _sync(device)
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def _render_and_grads(args: tuple, backend: str) -> tuple[Tensor, Tensor, list[Tensor]]:
    colors, alphas, _ = rasterization(*args, render_mode="RGB+ED", backend=backend)
    weights = torch.linspace(0.5, 1.5, colors.shape[-1], device=colors.device)
    loss = (colors[..., :3] * weights[:3]).sum() + alphas.sum() + 0.01 * colors[..., 3].sum()
    grads = torch.autograd.grad(loss, list(args[:5]))
    return colors.detach(), alphas.detach(), [g.detach() for g in grads]


def agreement(fast: str, device: torch.device, n: int, width: int, height: int) -> dict[str, float]:
    """Largest absolute differences fast backend vs reference (see the module docstring)."""
    args = random_scene(n, width, height, device)
    (c_f, a_f, g_f), (c_r, a_r, g_r) = _render_and_grads(args, fast), _render_and_grads(args, "reference")
    covered = (a_r[..., 0] >= ED_EPS) & (a_f[..., 0] >= ED_EPS)
    names = ("means", "quats", "scales", "opacities", "colors")
    out = {"rgb_max_abs": float((c_f[..., :3] - c_r[..., :3]).abs().max()),
           "alpha_max_abs": float((a_f - a_r).abs().max()),
           "expected_depth_max_abs_m": float((c_f[..., 3] - c_r[..., 3])[covered].abs().max()) if covered.any()
           else 0.0}
    for name, gf, gr in zip(names, g_f, g_r):
        out[f"grad_{name}_max_abs"] = float((gf - gr).abs().max())
        out[f"grad_{name}_max_ref"] = float(gr.abs().max())
    return out


def time_rasterizer(fast: str, device: torch.device, n: int, width: int, height: int, reps: int) -> float:
    args = random_scene(n, width, height, device, seed=1)
    return _median_ms(lambda: _render_and_grads(args, fast), device, reps)


def time_train_step(graph, log, fast: str, device: torch.device, reps: int) -> float:  # type: ignore[no-untyped-def]
    """Median ms of compose + render + L1 loss + backward at the log's frames (first camera set)."""
    batches = [b.to(device) for b in view_batches(log) if b.rgb is not None]
    for node in graph.nodes:
        for tensor in node.tensors().values():
            tensor.requires_grad_(True)
    state = {"i": 0}

    def step() -> None:
        batch = batches[state["i"] % len(batches)]
        state["i"] += 1
        render = render_composed(graph.at(batch.frame_idx), batch.cam_to_world, batch.Ks, batch.width, batch.height,
                                 with_node_ids=False, backend=fast, eps2d=graph.eps2d)
        (render.rgb - batch.rgb).abs().mean().backward()
        for node in graph.nodes:
            for tensor in node.tensors().values():
                tensor.grad = None

    return _median_ms(step, device, reps)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cpu", action="store_true", help="CPU backend instead of gsplat (runs without a GPU)")
    parser.add_argument("--tiny", action="store_true", help="small sizes (tests)")
    parser.add_argument("--iterations", type=int, default=None, help="reconstruction iterations (default: config's)")
    parser.add_argument("--reps", type=int, default=10)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    if not args.cpu and not torch.cuda.is_available():
        raise SystemExit("device_check: no CUDA device (use --cpu to run the CPU variant)")
    device = torch.device("cpu" if args.cpu else "cuda")
    fast = "cpu" if args.cpu else "gsplat"
    n, width, height = (64, 32, 24) if args.tiny else (20000, 480, 320)
    tiny_world = WorldConfig(num_frames=4, width=32, height=24, test_every=2, num_vehicles=(1, 2),
                             num_pedestrians=(1, 1), num_static=(0, 1))
    world = tiny_world if args.tiny else WorldConfig()
    iterations = args.iterations or (4 if args.tiny else ReconstructionConfig().iterations)
    config = replace(ReconstructionConfig(), iterations=iterations, backend=fast, device=device.type)

    report: dict = {"device": torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu",
                    "backend": fast, "torch": torch.__version__, "tiny": args.tiny}
    report["agreement"] = agreement(fast, device, n, width, height)
    logger.info("agreement: %s", report["agreement"])
    report["rasterizer_fwd_bwd_ms"] = time_rasterizer(fast, device, n, width, height, args.reps)
    log = generate_log(0, world)
    t0 = time.perf_counter()
    result = reconstruct(log, config)
    _sync(device)
    wall = time.perf_counter() - t0
    report["reconstruct"] = {"iterations": iterations, "wall_s": wall,
                             "metrics": {k: float(v) for k, v in result.metrics.items()
                                         if isinstance(v, (int, float))}}
    report["train_step_ms"] = time_train_step(result.graph, log, fast, device, args.reps)
    logger.info("rasterizer %.1f ms, train step %.1f ms, reconstruct %.1f s",
                report["rasterizer_fwd_bwd_ms"], report["train_step_ms"], wall)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(report, indent=2) + "\n")
    tmp.replace(args.out)
    return report


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main()
