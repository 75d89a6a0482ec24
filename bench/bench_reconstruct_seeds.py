"""Benchmark: reconstruction quality of the default synthetic sequence over many seeds, and where the error is.

    .venv/bin/python bench/bench_reconstruct_seeds.py --seeds 600-609 [--jobs 2] [--set densify.grad_threshold=1e-4]
                                                      [--iterations N] [--tag NAME] [--images DIR] [--out PATH]

For every seed it generates ``generate_log(seed, WorldConfig())`` (40 frames, 3 cameras at 240x160, every 10th
frame held out), reconstructs it with the default ``ReconstructionConfig`` (changed by ``--set``) and reports:

* held-out PSNR / SSIM of the full image and of the dynamic objects, and PSNR on eight evenly spaced training
  frames (a scene that is poor on its own training views is underfit, not only overfit);
* the error per region, held out and train: each region's share of the pixels, its share of the squared error
  and its PSNR. Regions come from the ground truth: ``dynamic`` (vehicles and pedestrians), ``static_objects``
  (cones, barriers, signs), ``sky`` (no depth), ``ground`` (back-projected below 0.3 m) and ``scenery``
  (buildings, trees, poles), the last two split at 30 m from the camera into ``_near`` and ``_far``.

``--set PATH=VALUE`` sets one field of the config by its dotted path (``loss.dssim=0.1``); ``lr.*.colors=0.02``
sets it for every node type. Seeds run in ``--jobs`` subprocesses (one thread each when there are as many jobs
as cores). Writes ``bench/results/reconstruct_seeds.json`` (or ``--out``); the table is logged.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from run_info import load_average, machine_info, write_json_result

logger = logging.getLogger("bench.reconstruct_seeds")
RESULTS = Path(__file__).resolve().parent / "results"
GROUND_HEIGHT_M = 0.3
NEAR_M = 30.0
TRAIN_FRAMES_SCORED = 8
REGIONS = ("dynamic", "static_objects", "sky", "ground_near", "ground_far", "scenery_near", "scenery_far")


def parse_seeds(text: str) -> list[int]:
    """``"600-609"`` or ``"500,503,7"`` (ranges inclusive) -> the seeds."""
    seeds: list[int] = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        seeds.extend(range(int(lo), int(hi or lo) + 1))
    return seeds


def _coerce(old: Any, text: str, path: str) -> Any:
    if isinstance(old, bool):
        if text.lower() not in ("true", "false"):
            raise ValueError(f"--set {path}: expected true or false, got {text!r}")
        return text.lower() == "true"
    if isinstance(old, int):
        return int(text)
    if isinstance(old, float):
        return float(text)
    return text


def _replace_path(obj: Any, parts: list[str], text: str, path: str) -> Any:
    name = parts[0]
    if name == "*":
        updates = {f.name: _replace_path(getattr(obj, f.name), parts[1:], text, path) for f in dataclasses.fields(obj)
                   if dataclasses.is_dataclass(getattr(obj, f.name))}
        return dataclasses.replace(obj, **updates)
    if not any(f.name == name for f in dataclasses.fields(obj)):
        raise ValueError(f"--set {path}: {type(obj).__name__} has no field {name!r}")
    old = getattr(obj, name)
    new = _replace_path(old, parts[1:], text, path) if len(parts) > 1 else _coerce(old, text, path)
    return dataclasses.replace(obj, **{name: new})


def configured(settings: list[str], iterations: int | None, threads: int, seed: int) -> Any:
    """The default ``ReconstructionConfig`` with ``PATH=VALUE`` settings applied."""
    from simsplat_core.scene import ReconstructionConfig  # noqa: PLC0415  # torch: loaded in workers only

    config = ReconstructionConfig(num_threads=threads, seed=seed)
    if iterations:
        config = dataclasses.replace(config, iterations=iterations)
    for item in settings:
        path, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--set expects PATH=VALUE, got {item!r}")
        config = _replace_path(config, path.split("."), value, path)
    return config


def region_masks(depth: np.ndarray, instance: np.ndarray, cam_to_world: np.ndarray, K: np.ndarray,
                 dynamic_ids: list[int]) -> dict[str, np.ndarray]:
    """``region -> [H, W] bool`` of one ground-truth view (the regions of the module docstring, disjoint)."""
    h, w = depth.shape
    ys, xs = np.mgrid[0:h, 0:w]
    finite = np.isfinite(depth) & (depth > 0)
    z = np.where(finite, depth, 0.0)
    cam = np.stack([(xs + 0.5 - K[0, 2]) / K[0, 0] * z, (ys + 0.5 - K[1, 2]) / K[1, 1] * z, z], -1)
    world = cam @ cam_to_world[:3, :3].T + cam_to_world[:3, 3]
    dist = np.linalg.norm(cam, axis=-1)
    dynamic = np.isin(instance, dynamic_ids)
    objects = (instance > 0) & ~dynamic
    rest = finite & (instance == 0)
    ground = rest & (world[..., 2] < GROUND_HEIGHT_M)
    scenery = rest & ~ground
    near = dist < NEAR_M
    return {"dynamic": dynamic, "static_objects": objects, "sky": ~finite & (instance == 0),
            "ground_near": ground & near, "ground_far": ground & ~near,
            "scenery_near": scenery & near, "scenery_far": scenery & ~near}


def region_errors(renders: list[Any], batches: list[Any], dynamic_ids: list[int]) -> dict[str, dict[str, float]]:
    """Per region over all ``renders``: pixel share, share of the squared error, PSNR."""
    sq = dict.fromkeys(REGIONS, 0.0)
    count = dict.fromkeys(REGIONS, 0)
    views = {(b.frame_idx, cam): (b, c) for b in batches for c, cam in enumerate(b.cameras)}
    for r in renders:
        batch, c = views[(r.frame_idx, r.camera)]
        err = np.square(r.rgb.astype(np.float64) - r.gt_rgb.astype(np.float64)).sum(-1)  # [H, W]
        masks = region_masks(batch.depth[c].numpy(), batch.instance[c].numpy(), batch.cam_to_world[c].numpy(),
                             batch.Ks[c].numpy(), dynamic_ids)
        for name, mask in masks.items():
            sq[name] += float(err[mask].sum())
            count[name] += int(mask.sum())
    total_sq, total_px = sum(sq.values()), sum(count.values())
    return {name: {"pixel_share": round(count[name] / max(total_px, 1), 4),
                   "error_share": round(sq[name] / max(total_sq, 1e-12), 4),
                   "psnr": round(10 * math.log10(3 * count[name] / sq[name]), 2) if sq[name] > 0 else math.nan}
            for name in REGIONS}


def save_error_sheet(renders: list[Any], path: Path) -> None:
    """Rows of held-out views: ground truth | render | 4x absolute error (PNG)."""
    import cv2  # noqa: PLC0415

    rows = [np.concatenate([r.gt_rgb, r.rgb, np.clip(4.0 * np.abs(r.rgb - r.gt_rgb), 0, 1)], axis=1) for r in renders]
    image = (np.clip(np.concatenate(rows, axis=0), 0, 1) * 255).round().astype(np.uint8)[..., ::-1]
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), image)


def run_seed(seed: int, settings: list[str], iterations: int | None, threads: int,
             images: Path | None = None) -> dict[str, Any]:
    """Reconstruct one seed; its figures and region errors (and its held-out error sheet in ``images``)."""
    from simsplat_core.scene import reconstruct  # noqa: PLC0415
    from simsplat_core.scene.evaluate import dynamic_instance_ids, render_views  # noqa: PLC0415
    from simsplat_core.scene.views import view_batches  # noqa: PLC0415
    from simsplat_core.world import WorldConfig, generate_log  # noqa: PLC0415

    log = generate_log(seed, WorldConfig())
    config = configured(settings, iterations, threads, seed)
    t0 = time.perf_counter()
    result = reconstruct(log, config)
    wall = time.perf_counter() - t0
    batches = view_batches(log)
    train = [b for b in batches if b.split == "train"]
    train = [train[i] for i in np.unique(np.linspace(0, len(train) - 1, TRAIN_FRAMES_SCORED).round().astype(int))]
    dyn = dynamic_instance_ids(log.objects)
    train_renders = render_views(result.graph, train, log.objects, config.backend, with_node_ids=False)
    m = result.metrics
    if images is not None:
        save_error_sheet(result.test_renders, images / f"seed{seed}_test_errors.png")
    return {
        "seed": seed, "wall_s": round(wall, 1), "num_gaussians": int(m["num_gaussians"]),
        "psnr_test": round(m["psnr_test"], 3), "ssim_test": round(m["ssim_test"], 4),
        "psnr_test_dynamic": round(m["psnr_test_dynamic"], 3),
        "psnr_train": round(float(np.mean([r.psnr for r in train_renders])), 3),
        "regions_test": region_errors(result.test_renders, batches, dyn),
        "regions_train": region_errors(train_renders, batches, dyn),
    }


def _worker(args: argparse.Namespace) -> None:
    row = run_seed(args.worker_seed, args.set, args.iterations, args.threads, args.images)
    sys.stdout.write("RESULT " + json.dumps(row) + "\n")


def _spawn(seed: int, args: argparse.Namespace, threads: int) -> subprocess.Popen:
    cmd = [sys.executable, __file__, "--worker-seed", str(seed), "--threads", str(threads)]
    cmd += [f"--set={s}" for s in args.set]
    if args.iterations:
        cmd += ["--iterations", str(args.iterations)]
    if args.images:
        cmd += ["--images", str(args.images)]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)


def _collect(proc: subprocess.Popen, seed: int) -> dict[str, Any]:
    out, _ = proc.communicate()
    for line in out.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT "):])
    raise RuntimeError(f"seed {seed}: worker exited with {proc.returncode} and no result")


def table(rows: list[dict[str, Any]]) -> list[str]:
    """Per seed: held-out / dynamic / train PSNR and the three regions with the largest error share."""
    lines = [f"{'seed':>5} {'test dB':>8} {'dyn dB':>7} {'train dB':>8} {'wall s':>7}  largest error shares (test)"]
    for r in rows:
        regions = sorted(r["regions_test"].items(), key=lambda kv: -kv[1]["error_share"])[:3]
        worst = ", ".join(f"{k} {v['error_share']:.2f} ({v['psnr']:.1f} dB)" for k, v in regions)
        lines.append(f"{r['seed']:>5} {r['psnr_test']:>8.2f} {r['psnr_test_dynamic']:>7.2f} {r['psnr_train']:>8.2f} "
                     f"{r['wall_s']:>7.0f}  {worst}")
    tests = [r["psnr_test"] for r in rows]
    dyns = [r["psnr_test_dynamic"] for r in rows]
    lines.append(f"{'mean':>5} {np.mean(tests):>8.2f} {np.mean(dyns):>7.2f} "
                 f"{np.mean([r['psnr_train'] for r in rows]):>8.2f}")
    lines.append(f"{'min':>5} {min(tests):>8.2f} {min(dyns):>7.2f}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=parse_seeds, default=parse_seeds("600-609"))
    parser.add_argument("--set", action="append", default=[], metavar="PATH=VALUE")
    parser.add_argument("--iterations", type=int, default=None)
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--threads", type=int, default=0, help="threads per job (0: cores / jobs)")
    parser.add_argument("--images", type=Path, default=None, help="save each seed's held-out error sheet here")
    parser.add_argument("--tag", default="", help="a name for this configuration in the JSON")
    parser.add_argument("--out", type=Path, default=RESULTS / "reconstruct_seeds.json")
    parser.add_argument("--worker-seed", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    if args.worker_seed is not None:
        _worker(args)
        return
    configured(args.set, args.iterations, 1, 0)  # a bad --set fails here, before any work
    threads = args.threads or max(1, (os.cpu_count() or 1) // args.jobs)
    header = {"machine": machine_info(), "load_average_before": load_average(), "jobs": args.jobs,
              "threads_per_job": threads, "tag": args.tag, "settings": args.set, "iterations": args.iterations,
              "seeds": args.seeds}
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    pending = list(args.seeds)
    running: dict[int, subprocess.Popen] = {}
    while pending or running:
        while pending and len(running) < args.jobs:
            seed = pending.pop(0)
            running[seed] = _spawn(seed, args, threads)
        done = [seed for seed, proc in running.items() if proc.poll() is not None]
        if not done:
            time.sleep(1.0)
            continue
        for seed in done:
            rows.append(_collect(running.pop(seed), seed))
            logger.info("seed %d: test %.2f dB, dynamic %.2f dB, train %.2f dB (%d of %d done)", seed,
                        rows[-1]["psnr_test"], rows[-1]["psnr_test_dynamic"], rows[-1]["psnr_train"], len(rows),
                        len(args.seeds))
        _write(header, rows, t0, args.out, complete=not (pending or running))
    for line in table(sorted(rows, key=lambda r: r["seed"])):
        logger.info("%s", line)


def _write(header: dict[str, Any], rows: list[dict[str, Any]], t0: float, out: Path, complete: bool) -> None:
    """The JSON so far (written after every seed, so an interrupted run keeps the seeds it finished)."""
    rows = sorted(rows, key=lambda r: r["seed"])
    write_json_result({
        **header, "complete": complete, "load_average_after": load_average(),
        "wall_s": round(time.perf_counter() - t0, 1),
        "mean_psnr_test": round(float(np.mean([r["psnr_test"] for r in rows])), 3),
        "min_psnr_test": min(r["psnr_test"] for r in rows),
        "min_psnr_test_dynamic": min(r["psnr_test_dynamic"] for r in rows),
        "rows": rows, "table": table(rows),
    }, out)


if __name__ == "__main__":
    main()
