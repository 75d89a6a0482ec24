"""Benchmark: Gaussian rasterizer forward+backward time and peak memory on the CPU.

    .venv/bin/python bench/bench_rasterizer.py [--reps 5] [--sizes 10000 50000 200000] [--no-gsplat]

For N in {10k, 50k, 200k} Gaussians x {3 cameras at 240x160, 1 camera at 960x640} it measures:

* ``cpu``: this package's CPU backend (``rasterization(..., backend="cpu")`` then ``backward()``);
* ``reference``: the dense pure-torch reference. It is O(C H W N) in time and memory, so it is run on a
  subsample (``N_sub`` Gaussians at a quarter of the resolution) and its time / memory per
  (pixel, Gaussian) pair are **extrapolated** to the full case (labelled ``extrapolated``);
* ``gsplat-torch``: gsplat 1.5.3's pure-torch implementation (``gsplat/cuda/_torch_impl.py``) where it
  runs on a CPU: ``_fully_fused_projection`` fwd+bwd (full size) and ``_isect_tiles`` (a Python loop
  per Gaussian: timed on a subsample and extrapolated per visible Gaussian). Its compositing
  (``_rasterize_to_pixels``) cannot run without CUDA: it calls ``rasterize_to_indices_in_range`` from
  gsplat's compiled CUDA extension and needs ``nerfacc``; the reason is recorded.

Each case runs in a fresh subprocess: numba kernels are loaded/compiled on a tiny warm-up scene first,
then wall time is taken over ``--reps`` runs (min and median reported). Peak memory is
``ru_maxrss`` (peak RSS) after the timed runs minus the RSS just before them, read in that subprocess
(tracemalloc does not see torch/numba allocations). A profile of the CPU backend (per stage) follows.
Scenes are a driving corridor: road, facades and objects along a 200 m trajectory, cameras at z = 0;
scales log-uniform in [0.05, 0.5] m, opacities uniform in [0.1, 0.99]; the table reports how many
Gaussians each pixel composites (estimated on 512 sampled pixels).

Prints a table (logging) and writes ``bench/results/rasterizer.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import logging
import math
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch

logger = logging.getLogger("bench.rasterizer")

CAMERA_SETUPS = {"3x240x160": (3, 240, 160), "1x960x640": (1, 960, 640)}
REFERENCE_SUBSAMPLE = 2000  # Gaussians
REFERENCE_DOWNSCALE = 4  # image side divisor for the reference run
GSPLAT_ISECT_SUBSAMPLE = 4000  # Gaussians


def make_scene(n: int, n_cams: int, width: int, height: int, seed: int = 0, dtype: torch.dtype = torch.float32):
    """A driving corridor: ``(means, quats, scales, opacities, colors, viewmats, Ks)``.

    World axes follow OpenCV (x right, y down, z forward); the road is the plane y = 1.5 (camera height
    1.5 m). 35 % of the Gaussians lie on the road (|x| < 8), 35 % on facades (|x| in [9, 13], 12 m
    tall), 30 % on objects above the road (cars, poles; 2 m tall), all with z uniform in [-60, 140].
    Cameras sit at the origin with a 70 degree horizontal field of view, yawed -55..55 degrees.
    """
    g = torch.Generator().manual_seed(seed)

    def rand(*shape: int) -> torch.Tensor:
        return torch.rand(*shape, generator=g, dtype=dtype)

    n_road, n_facade = int(0.35 * n), int(0.35 * n)
    n_obj = n - n_road - n_facade
    along = lambda k: -60.0 + 200.0 * rand(k)  # noqa: E731
    side = torch.where(rand(n_facade) < 0.5, -1.0, 1.0).to(dtype)
    means = torch.cat([
        torch.stack([-8.0 + 16.0 * rand(n_road), 1.5 + 0.05 * rand(n_road), along(n_road)], -1),
        torch.stack([side * (9.0 + 4.0 * rand(n_facade)), 1.5 - 12.0 * rand(n_facade), along(n_facade)], -1),
        torch.stack([-8.0 + 16.0 * rand(n_obj), 1.5 - 2.0 * rand(n_obj), along(n_obj)], -1),
    ])
    quats = torch.randn(n, 4, generator=g, dtype=dtype)
    scales = torch.exp(math.log(0.05) + (math.log(0.5) - math.log(0.05)) * rand(n, 3))
    opacities = 0.1 + 0.89 * rand(n)
    colors = rand(n, 3)
    focal = width / (2.0 * math.tan(math.radians(35.0)))
    K = torch.tensor([[focal, 0.0, width / 2], [0.0, focal, height / 2], [0.0, 0.0, 1.0]], dtype=dtype)
    yaws = [0.0] if n_cams == 1 else np.radians(np.linspace(-55.0, 55.0, n_cams)).tolist()
    viewmats = []
    for yaw in yaws:
        cam_to_world = torch.tensor([[math.cos(yaw), 0.0, math.sin(yaw)], [0.0, 1.0, 0.0],
                                     [-math.sin(yaw), 0.0, math.cos(yaw)]], dtype=dtype)
        vm = torch.eye(4, dtype=dtype)
        vm[:3, :3] = cam_to_world.T
        viewmats.append(vm)
    return means, quats, scales, opacities, colors, torch.stack(viewmats), K.repeat(n_cams, 1, 1)


# ----------------------------------------------------------------------------------------------- worker


def _rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _peak_bytes() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB


def _timed(fn: Callable[[], Any], reps: int) -> dict[str, float]:
    """Run ``fn`` ``reps`` times; wall times and the peak-RSS increase over the RSS before the first run."""
    rss_before = _rss_bytes()
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return {"min_s": min(times), "median_s": statistics.median(times),
            "peak_mem_mb": max(_peak_bytes() - rss_before, 0) / 2**20}


def _leaves(tensors):
    return [t.detach().clone().requires_grad_(True) for t in tensors]


def _contributions_per_pixel(means, quats, scales, opacities, viewmats, Ks, width, height, samples=512) -> float:
    """Mean number of Gaussians composited per pixel (alpha >= 1/255 before T <= 1e-4), camera 0,
    ``samples`` random pixels (tile-range rule ignored; an estimate)."""
    from simsplat_core.render import project_gaussians

    with torch.no_grad():
        proj = project_gaussians(means, quats, scales, viewmats[:1], Ks[:1], width, height)
        vis = torch.nonzero(proj.radii[0] > 0).reshape(-1)
        order = vis[torch.argsort(proj.depths[0, vis], stable=True)]
        m, q, o = proj.means2d[0, order], proj.conics[0, order], opacities[order]
        g = torch.Generator().manual_seed(0)
        px = torch.randint(0, width, (samples,), generator=g) + 0.5
        py = torch.randint(0, height, (samples,), generator=g) + 0.5
        counts = []
        for chunk in range(0, samples, 64):
            dx = m[None, :, 0] - px[chunk:chunk + 64, None]
            dy = m[None, :, 1] - py[chunk:chunk + 64, None]
            sigma = 0.5 * (q[None, :, 0] * dx**2 + q[None, :, 2] * dy**2) + q[None, :, 1] * dx * dy
            alpha = torch.clamp(o[None] * torch.exp(-sigma), max=0.999)
            alpha = torch.where((sigma >= 0) & (alpha >= 1 / 255), alpha, torch.zeros_like(alpha))
            alive = torch.cumprod(1 - alpha, dim=1) > 1e-4
            counts.append(((alpha > 0) & alive).sum(dim=1).float())
        return float(torch.cat(counts).mean())


def _case_cpu(n: int, setup: str, reps: int) -> dict[str, Any]:
    from simsplat_core.render import rasterization

    n_cams, width, height = CAMERA_SETUPS[setup]
    scene = make_scene(n, n_cams, width, height)
    means, quats, scales, opacities, colors, viewmats, Ks = scene
    warm = make_scene(200, 1, 32, 24)
    warm_leaves = _leaves(warm[:5])
    out = rasterization(*warm_leaves, warm[5], warm[6], 32, 24, backend="cpu")
    (out[0].sum() + out[1].sum()).backward()
    stats: dict[str, Any] = {}

    def run() -> None:
        leaves = _leaves(scene[:5])
        col, alpha, meta = rasterization(*leaves, viewmats, Ks, width, height, backend="cpu")
        (col.sum() + alpha.sum()).backward()
        stats.update(visible=int((meta.radii > 0).sum()), n_isects=meta.n_isects)

    result = _timed(run, reps)
    result.update(stats)
    result["contributions_per_pixel"] = _contributions_per_pixel(means, quats, scales, opacities, viewmats, Ks,
                                                                 width, height)
    return result


def _case_reference(n: int, setup: str, reps: int) -> dict[str, Any]:
    from simsplat_core.render import rasterization

    n_cams, width, height = CAMERA_SETUPS[setup]
    n_sub = min(n, REFERENCE_SUBSAMPLE)
    w_sub, h_sub = width // REFERENCE_DOWNSCALE, height // REFERENCE_DOWNSCALE
    scene = make_scene(n_sub, n_cams, w_sub, h_sub, seed=1)

    def run() -> None:
        col, alpha, _ = rasterization(*_leaves(scene[:5]), scene[5], scene[6], w_sub, h_sub, backend="reference")
        (col.sum() + alpha.sum()).backward()

    run()  # warm-up
    sub = _timed(run, max(1, reps // 2))
    pairs_sub = n_cams * w_sub * h_sub * n_sub
    pairs_full = n_cams * width * height * n
    factor = pairs_full / pairs_sub
    return {"min_s": sub["min_s"] * factor, "median_s": sub["median_s"] * factor,
            "peak_mem_mb": sub["peak_mem_mb"] * factor, "extrapolated": True,
            "measured": {"n": n_sub, "width": w_sub, "height": h_sub, **sub},
            "ns_per_pixel_gaussian_pair": sub["min_s"] / pairs_sub * 1e9}


def _case_gsplat_torch(n: int, setup: str, reps: int) -> dict[str, Any]:
    try:
        from gsplat.cuda import _torch_impl as gs
    except ImportError as exc:  # optional dependency
        return {"error": f"gsplat not importable: {exc}"}
    n_cams, width, height = CAMERA_SETUPS[setup]
    scene = make_scene(n, n_cams, width, height)
    viewmats, Ks = scene[5], scene[6]
    tile_width, tile_height = math.ceil(width / 16), math.ceil(height / 16)

    def project():
        means, quats, scales = _leaves(scene[:3])
        covars, _ = gs._quat_scale_to_covar_preci(quats, scales, True, False, triu=False)
        return gs._fully_fused_projection(means, covars, viewmats, Ks, width, height)

    def run_projection() -> None:
        radii, means2d, depths, conics, _ = project()
        (means2d.sum() + conics.sum() + depths.sum()).backward()

    run_projection()
    result: dict[str, Any] = {"projection_fwd_bwd": _timed(run_projection, reps)}

    radii, means2d, depths, conics, _ = project()
    n_sub = min(n, GSPLAT_ISECT_SUBSAMPLE)
    sub = slice(0, n_sub)
    visible_sub = int((radii[:, sub] > 0).all(dim=-1).sum())
    visible = int((radii > 0).all(dim=-1).sum())
    start = time.perf_counter()
    gs._isect_tiles(means2d[:, sub].detach(), radii[:, sub], depths[:, sub].detach(), 16, tile_width, tile_height)
    isect_s = (time.perf_counter() - start) * (n / n_sub)  # its Python loop visits every (camera, Gaussian)
    result["isect_tiles_s"] = isect_s
    result["isect_tiles_extrapolated"] = n_sub < n
    result["isect_tiles_visible_sub"] = visible_sub
    result["visible"] = visible
    # Not called: _rasterize_to_pixels -> gsplat.cuda._wrapper.rasterize_to_indices_in_range is a lazy CUDA
    # function whose first call JIT-compiles gsplat's CUDA extension (writes ~/.cache/torch_extensions).
    nerfacc = importlib.util.find_spec("nerfacc") is not None
    result["rasterize"] = ("not run on CPU: gsplat's torch _rasterize_to_pixels calls "
                           "rasterize_to_indices_in_range from the compiled CUDA extension (no CUDA here) and "
                           f"needs nerfacc (installed: {nerfacc})")
    return result


def _profile_cpu(n: int, setup: str, reps: int) -> dict[str, Any]:
    """Stage times of the CPU backend (min over ``reps``), from the public stage functions and kernels."""
    import numba

    from simsplat_core.render import cpu_kernels, isect_tiles, project_gaussians, rasterize_to_pixels, tile_grid

    n_cams, width, height = CAMERA_SETUPS[setup]
    scene = make_scene(n, n_cams, width, height)
    viewmats, Ks = scene[5], scene[6]
    tile_width, tile_height = tile_grid(width, height, 16)
    times: dict[str, list[float]] = {}

    def lap(name: str, start: float) -> float:
        now = time.perf_counter()
        times.setdefault(name, []).append(now - start)
        return now

    for _ in range(reps + 1):  # first round warms up
        means, quats, scales, opacities, colors = _leaves(scene[:5])
        t0 = time.perf_counter()
        proj = project_gaussians(means, quats, scales, viewmats, Ks, width, height)
        t = lap("1 projection fwd (fused numba)", t0)
        isects = isect_tiles(proj.means2d, proj.radii, proj.depths, 16, tile_width, tile_height)
        t = lap("2 binning (torch depth sort + numba counting sort)", t)
        col_cn = colors[None].expand(n_cams, n, 3)
        op_cn = opacities[None].expand(n_cams, n)
        col, alpha = rasterize_to_pixels(proj.means2d, proj.conics, col_cn, op_cn, width, height, 16,
                                         isects.isect_offsets, isects.flatten_ids)
        t = lap("3 compositing fwd (pack + numba kernel)", t)
        marks: dict[str, float] = {}

        def mark(grad: torch.Tensor, marks: dict[str, float] = marks) -> None:
            marks.setdefault("means2d", time.perf_counter())

        proj.means2d.register_hook(mark)
        t_bwd = time.perf_counter()
        (col.sum() + alpha.sum()).backward()
        t_end = time.perf_counter()
        times.setdefault("4 compositing bwd (numba kernel + row reduction)", []).append(marks["means2d"] - t_bwd)
        times.setdefault("5 projection bwd (fused numba) + broadcasts", []).append(t_end - marks["means2d"])

    # kernel-level split of compositing (direct calls on the last round's data)
    flat = n_cams * n
    m2 = proj.means2d.detach().numpy().reshape(flat, 2)
    con = proj.conics.detach().numpy().reshape(flat, 3)
    ops = np.ascontiguousarray(op_cn.detach().numpy().reshape(flat))
    cols = np.ascontiguousarray(col_cn.detach().numpy().reshape(flat, 3))
    offsets = np.append(isects.isect_offsets.numpy().reshape(-1), isects.n_isects).astype(np.int64)
    ids = isects.flatten_ids.numpy()
    order = np.arange(offsets.shape[0] - 1, dtype=np.int64)
    bgs = np.zeros((n_cams, 3), np.float32)
    kernel_times: dict[str, list[float]] = {}
    for _ in range(reps):
        t0 = time.perf_counter()
        rec = cpu_kernels.pack_records(m2, con, ops)
        t1 = time.perf_counter()
        render = np.empty((n_cams, height, width, 3), np.float32)
        t_final = np.empty((n_cams, height, width))
        last = np.empty((n_cams, height, width), np.int64)
        with numba.parallel_chunksize(1):
            cpu_kernels.rasterize_fwd(rec, cols, bgs, offsets, ids, order, width, height, 16, tile_width, render,
                                      t_final, last)
        t2 = time.perf_counter()
        rows = np.empty((ids.shape[0], 9), np.float32)
        hit = np.zeros(ids.shape[0], np.uint8)
        v_render = np.ones((n_cams, height, width, 3), np.float32)
        v_alpha = np.ones((n_cams, height, width), np.float32)
        t3 = time.perf_counter()
        with numba.parallel_chunksize(1):
            cpu_kernels.rasterize_bwd(rec, cols, bgs, offsets, ids, order, width, height, 16, tile_width, t_final,
                                      last, v_render, v_alpha, rows, hit)
        t4 = time.perf_counter()
        cpu_kernels.reduce_rows(rows, hit, ids, np.ascontiguousarray(offsets[:: offsets.shape[0] // n_cams]), flat)
        t5 = time.perf_counter()
        for name, dt in (("pack_records", t1 - t0), ("rasterize_fwd kernel", t2 - t1),
                         ("rasterize_bwd kernel", t4 - t3), ("reduce_rows", t5 - t4)):
            kernel_times.setdefault(name, []).append(dt)
    return {"stages_s": {k: min(v[1:]) for k, v in times.items()},
            "kernels_s": {k: min(v) for k, v in kernel_times.items()},
            "n_isects": isects.n_isects, "contributing_isects": int(hit.sum())}


WORKERS = {"cpu": _case_cpu, "reference": _case_reference, "gsplat-torch": _case_gsplat_torch,
           "profile": _profile_cpu}


# ----------------------------------------------------------------------------------------------- driver


def _run_subprocess(kind: str, n: int, setup: str, reps: int) -> dict[str, Any]:
    cmd = [sys.executable, __file__, "--worker", kind, "--n", str(n), "--setup", setup, "--reps", str(reps)]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=Path(__file__).resolve().parents[1])
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else f"rc {proc.returncode}"}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _fmt_ms(seconds: float | None) -> str:
    return "-" if seconds is None else f"{seconds * 1e3:,.0f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000, 50_000, 200_000])
    parser.add_argument("--setups", nargs="+", default=list(CAMERA_SETUPS))
    parser.add_argument("--no-gsplat", action="store_true", help="skip gsplat's torch implementation")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "rasterizer.json")
    parser.add_argument("--worker", choices=sorted(WORKERS), help=argparse.SUPPRESS)
    parser.add_argument("--n", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--setup", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        torch.set_grad_enabled(True)
        print(json.dumps(WORKERS[args.worker](args.n, args.setup, args.reps)))
        return
    logging.basicConfig(level=logging.INFO, format="%(message)s")

    rows = []
    for setup in args.setups:
        for n in args.sizes:
            row: dict[str, Any] = {"n": n, "setup": setup}
            row["cpu"] = _run_subprocess("cpu", n, setup, args.reps)
            row["reference"] = _run_subprocess("reference", n, setup, args.reps)
            if not args.no_gsplat:
                row["gsplat_torch"] = _run_subprocess("gsplat-torch", n, setup, max(1, args.reps // 2))
            rows.append(row)
            logger.info("done %s N=%d: cpu %s ms", setup, n, _fmt_ms(row["cpu"].get("min_s")))
    profile = {setup: _run_subprocess("profile", max(args.sizes), setup, args.reps) for setup in args.setups}

    header = (f"{'cameras':<10} {'N':>8} {'visible':>8} {'isects':>9} {'px-comp':>7} | {'cpu ms':>7} {'med':>7} "
              f"{'MB':>6} | {'ref ms*':>10} {'ref MB*':>9} {'ref/cpu':>8} | {'gs proj':>8} {'gs isect':>9} "
              f"{'(gs p+i)/cpu':>12}")
    lines = [header, "-" * len(header)]
    for row in rows:
        cpu, ref, gst = row["cpu"], row["reference"], row.get("gsplat_torch", {})
        gs_proj = gst.get("projection_fwd_bwd", {}).get("min_s")
        gs_isect = gst.get("isect_tiles_s")
        ratio_ref = ref.get("min_s", math.nan) / cpu.get("min_s", math.nan)
        ratio_gs = ((gs_proj + gs_isect) / cpu["min_s"]) if gs_proj is not None and gs_isect is not None else None
        lines.append(
            f"{row['setup']:<10} {row['n']:>8,} {cpu.get('visible', 0):>8,} {cpu.get('n_isects', 0):>9,} "
            f"{cpu.get('contributions_per_pixel', math.nan):>7.1f} | {_fmt_ms(cpu.get('min_s')):>7} "
            f"{_fmt_ms(cpu.get('median_s')):>7} {cpu.get('peak_mem_mb', math.nan):>6.0f} | "
            f"{_fmt_ms(ref.get('min_s')):>10} {ref.get('peak_mem_mb', math.nan):>9,.0f} {ratio_ref:>7.0f}x | "
            f"{_fmt_ms(gs_proj):>8} {_fmt_ms(gs_isect):>9} {('-' if ratio_gs is None else f'{ratio_gs:.1f}x'):>12}")
    lines.append("cpu = forward+backward of rasterization(backend='cpu'), min over reps; MB = peak RSS increase.")
    lines.append(f"* reference extrapolated from {REFERENCE_SUBSAMPLE} Gaussians at 1/{REFERENCE_DOWNSCALE} "
                 "resolution per (pixel, Gaussian) pair.")
    lines.append("gs proj = gsplat _torch_impl projection fwd+bwd; gs isect = its _isect_tiles (Python loop, "
                 "extrapolated from a subsample); its compositing cannot run on a CPU (see JSON).")
    lines.append("px-comp = Gaussians composited per pixel (estimate, camera 0).")
    for setup, prof in profile.items():
        if "error" in prof:
            lines.append(f"profile {setup}: {prof['error']}")
            continue
        total = sum(prof["stages_s"].values())
        lines.append(f"profile cpu backend, N={max(args.sizes):,}, {setup} "
                     f"(min over reps; total {total * 1e3:.0f} ms):")
        for name, sec in prof["stages_s"].items():
            lines.append(f"  {name:<52} {sec * 1e3:7.1f} ms  {100 * sec / total:5.1f} %")
        for name, sec in prof["kernels_s"].items():
            lines.append(f"    kernel {name:<45} {sec * 1e3:7.1f} ms")
    for line in lines:
        logger.info(line)

    result = {
        "machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                    "python": platform.python_version(), "torch": torch.__version__,
                    "numba_threads": int(os.environ.get("NUMBA_NUM_THREADS", os.cpu_count() or 1))},
        "method": {"time": f"wall clock, fresh subprocess per case, min/median over {args.reps} reps after a "
                           "warm-up that loads the numba kernels",
                   "memory": "ru_maxrss after the timed reps minus RSS before them (same subprocess)",
                   "reference": f"extrapolated per (pixel, Gaussian) pair from {REFERENCE_SUBSAMPLE} Gaussians at "
                                f"1/{REFERENCE_DOWNSCALE} resolution",
                   "gsplat_torch": "gsplat 1.5.3 gsplat/cuda/_torch_impl.py; projection fwd+bwd timed at full "
                                   "size, _isect_tiles extrapolated from a subsample, compositing not runnable "
                                   "on CPU"},
        "cases": rows,
        "profile": profile,
        "table": lines,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    logger.info("wrote %s", args.out)


if __name__ == "__main__":
    main()
