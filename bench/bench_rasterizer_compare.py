"""Benchmark: the CPU rasterizer of this tree against a base revision, side by side in one process.

    .venv/bin/python bench/bench_rasterizer_compare.py [--base main] [--reps 9] \
        [--cases 50000:3x240x160 10000:3x240x160 200000:3x240x160 50000:1x960x640]

The base revision's ``simsplat_core/render`` is read with ``git show`` and imported as a separate
package (``rasterizer_base.render``, absolute imports rewritten), so both versions run in the same
process, with the same threads, on the same scene (``bench_rasterizer.make_scene``). For every case
both versions are warmed up, then forward+backward of ``rasterization(..., backend="cpu")`` is timed
``--reps`` times per version, alternating base / new so that load from other processes hits both
alike. Reported per case: min and median of each, ``new / base`` for both, and the largest difference
of the outputs and of the input gradients between the versions (a sanity check, not a test).

Writes ``bench/results/rasterizer_compare.json``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_rasterizer import CAMERA_SETUPS, make_scene  # noqa: E402
from run_info import write_json_result  # noqa: E402

logger = logging.getLogger("bench.rasterizer_compare")

REPO = Path(__file__).resolve().parent.parent
RENDER_DIR = "simsplat_core/render"
BASE_PACKAGE = "rasterizer_base"
DEFAULT_CASES = ["50000:3x240x160", "10000:3x240x160", "200000:3x240x160", "50000:1x960x640"]

Rasterize = Callable[..., tuple[torch.Tensor, torch.Tensor, Any]]


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=REPO, check=True, capture_output=True, text=True).stdout


def import_base(rev: str) -> tuple[Rasterize, str]:
    """``rasterization`` of ``simsplat_core/render`` at ``rev`` and the commit it resolved to.

    The files go to ``<tmp>/rasterizer_base_<commit>/rasterizer_base/render`` (kept, so numba's on-disk
    cache of the base kernels survives between runs)."""
    commit = _git("rev-parse", rev).strip()
    root = Path(tempfile.gettempdir()) / f"rasterizer_base_{commit[:12]}"
    package = root / BASE_PACKAGE / "render"
    package.mkdir(parents=True, exist_ok=True)
    (root / BASE_PACKAGE / "__init__.py").write_text("")
    for name in _git("ls-tree", "--name-only", f"{commit}:{RENDER_DIR}").split():
        if name.endswith(".py"):
            source = _git("show", f"{commit}:{RENDER_DIR}/{name}")
            text = source.replace("simsplat_core.render", f"{BASE_PACKAGE}.render")
            target = package / name
            if not target.exists() or target.read_text() != text:
                target.write_text(text)
    sys.path.insert(0, str(root))
    module = importlib.import_module(f"{BASE_PACKAGE}.render")
    return module.rasterization, commit


def _leaves(tensors: tuple[torch.Tensor, ...]) -> list[torch.Tensor]:
    return [t.detach().clone().requires_grad_(True) for t in tensors]


def _fwd_bwd(rasterize: Rasterize, scene: tuple[torch.Tensor, ...], width: int, height: int,
             ) -> tuple[float, list[torch.Tensor]]:
    """Seconds for one forward+backward and ``[render, alphas, grads of means, quats, scales,
    opacities, colors]``."""
    leaves = _leaves(scene[:5])
    start = time.perf_counter()
    render, alphas, _ = rasterize(*leaves, scene[5], scene[6], width, height, backend="cpu")
    (render.sum() + alphas.sum()).backward()
    seconds = time.perf_counter() - start
    return seconds, [render.detach(), alphas.detach()] + [leaf.grad for leaf in leaves]


def _max_abs_diff(a: list[torch.Tensor], b: list[torch.Tensor]) -> list[float]:
    return [float((x.double() - y.double()).abs().max()) for x, y in zip(a, b, strict=True)]


def compare_case(base: Rasterize, new: Rasterize, n: int, setup: str, reps: int) -> dict[str, Any]:
    """Interleaved timing of one scene: ``{"base": {min_s, median_s}, "new": {...}, ratios, diffs}``."""
    n_cams, width, height = CAMERA_SETUPS[setup]
    scene = make_scene(n, n_cams, width, height)
    warm = make_scene(200, 1, 32, 24)
    for rasterize in (base, new):
        _fwd_bwd(rasterize, warm, 32, 24)
        _fwd_bwd(rasterize, scene, width, height)
    times: dict[str, list[float]] = {"base": [], "new": []}
    outputs: dict[str, list[torch.Tensor]] = {}
    for rep in range(reps):
        order = [("base", base), ("new", new)] if rep % 2 == 0 else [("new", new), ("base", base)]
        for name, rasterize in order:
            seconds, outputs[name] = _fwd_bwd(rasterize, scene, width, height)
            times[name].append(seconds)
    stats = {name: {"min_s": min(ts), "median_s": statistics.median(ts), "times_s": ts} for name, ts in times.items()}
    return {
        "n": n, "setup": setup, **stats,
        "ratio_min": stats["new"]["min_s"] / stats["base"]["min_s"],
        "ratio_median": stats["new"]["median_s"] / stats["base"]["median_s"],
        "max_abs_diff": dict(zip(["render", "alphas", "v_means", "v_quats", "v_scales", "v_opacities", "v_colors"],
                                 _max_abs_diff(outputs["base"], outputs["new"]), strict=True)),
    }


def main() -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="main", help="git revision to compare against")
    parser.add_argument("--reps", type=int, default=9)
    parser.add_argument("--cases", nargs="+", default=DEFAULT_CASES, help="N:setup, setup in "
                        f"{sorted(CAMERA_SETUPS)}")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "results" / "rasterizer_compare.json")
    args = parser.parse_args()

    base, base_commit = import_base(args.base)
    from simsplat_core.render import rasterization as new

    new_commit = _git("rev-parse", "HEAD").strip()
    dirty = bool(_git("status", "--porcelain", "--", RENDER_DIR).strip())
    rows = []
    for case in args.cases:
        n_text, setup = case.split(":")
        row = compare_case(base, new, int(n_text), setup, args.reps)
        rows.append(row)
        logger.info("%s N=%s: base min %.1f med %.1f ms | new min %.1f med %.1f ms | new/base min %.2f med %.2f",
                    setup, n_text, row["base"]["min_s"] * 1e3, row["base"]["median_s"] * 1e3,
                    row["new"]["min_s"] * 1e3, row["new"]["median_s"] * 1e3, row["ratio_min"], row["ratio_median"])
        logger.info("  max |new - base|: %s", ", ".join(f"{k} {v:.2e}" for k, v in row["max_abs_diff"].items()))
    result = {
        "command": " ".join([Path(sys.executable).name, *sys.argv]),
        "base_commit": base_commit, "new_commit": new_commit, "new_render_dir_dirty": dirty,
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                    "load_avg_1min_at_end": os.getloadavg()[0], "python": platform.python_version(),
                    "torch": torch.__version__},
        "method": f"forward+backward wall time, {args.reps} reps per version after warm-up, base and new "
                  "alternated in one process (order swapped every rep)",
        "cases": rows,
    }
    write_json_result(result, args.out)


if __name__ == "__main__":
    main()
