"""Benchmark: a reconstruction-sized workload in two local Ray workers at Ray's default niceness (15) and at the
driver's (0), the way ``make demo`` runs its two reconstructions.

    .venv/bin/python bench/bench_ray_niceness.py [--rounds 2] [--iterations 8] [--busy 0]

Each round starts a local Ray instance with 2 CPUs for each setting in turn (interleaved, so both see the same
machine load) and runs two tasks at once, one thread each, each doing ``--iterations`` forward+backward passes of
the CPU rasterizer (50k Gaussians, 3 x 240 x 160: the scale of one reconstruction step). ``--busy N`` adds N
nice-0 busy processes beside them (a loaded machine: a Prefect server, other jobs). Reports seconds per iteration
(median over tasks and rounds), the workers' niceness as they saw it, the load average, and the ratio; writes
``bench/results/ray_niceness.json``.
"""

from __future__ import annotations

import argparse
import logging
import multiprocessing
import os
import statistics
import time
from pathlib import Path

from bench_rasterizer import make_scene
from run_info import load_average, machine_info, write_json_result

logger = logging.getLogger("bench.ray_niceness")

SETTINGS = {"ray default (niceness 15)": None, "driver's priority (niceness 0)": "0"}


def _raster_iterations(iterations: int) -> tuple[float, int]:
    """Seconds per forward+backward iteration in this process (1 thread) and its niceness."""
    from simsplat_core.compute_threads import set_compute_threads
    from simsplat_core.render import rasterization

    set_compute_threads(1)
    scene = make_scene(50_000, 3, 240, 160)
    leaves = [t.detach().clone().requires_grad_(True) for t in scene[:5]]
    rasterization(*leaves, scene[5], scene[6], 32, 24, backend="cpu")  # numba load / compile
    start = time.perf_counter()
    for _ in range(iterations):
        col, alpha, _ = rasterization(*leaves, scene[5], scene[6], 240, 160, backend="cpu")
        (col.sum() + alpha.sum()).backward()
    return (time.perf_counter() - start) / iterations, os.nice(0)


def _busy(stop_at: float) -> None:
    while time.time() < stop_at:
        pass


def _run_setting(niceness: str | None, iterations: int) -> list[tuple[float, int]]:
    import ray

    env = {"RAY_worker_niceness": niceness} if niceness is not None else {}
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, runtime_env={"env_vars": env})
    try:
        remote = ray.remote(num_cpus=1)(_raster_iterations)
        return ray.get([remote.remote(iterations) for _ in range(2)])
    finally:
        ray.shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--iterations", type=int, default=8)
    parser.add_argument("--busy", type=int, default=0, help="nice-0 busy processes beside the workers")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    per_setting: dict[str, list[float]] = {name: [] for name in SETTINGS}
    seen_niceness: dict[str, set[int]] = {name: set() for name in SETTINGS}
    load_before = load_average()
    for round_index in range(args.rounds):
        for name, niceness in SETTINGS.items():
            busy = [multiprocessing.Process(target=_busy, args=(time.time() + 3600,)) for _ in range(args.busy)]
            for proc in busy:
                proc.start()
            try:
                results = _run_setting(niceness, args.iterations)
            finally:
                for proc in busy:
                    proc.terminate()
            per_setting[name] += [s for s, _ in results]
            seen_niceness[name] |= {n for _, n in results}
            logger.info("round %d, %s: %s s/it", round_index, name, ", ".join(f"{s:.3f}" for s, _ in results))
    medians = {name: statistics.median(times) for name, times in per_setting.items()}
    default, driver = (medians[name] for name in SETTINGS)
    result = {
        "machine": machine_info(), "load_average_before": load_before, "load_average_after": load_average(),
        "busy_processes": args.busy, "rounds": args.rounds, "iterations_per_task": args.iterations,
        "workload": "2 Ray tasks at once, 1 thread each: CPU rasterizer fwd+bwd, 50k Gaussians, 3 x 240 x 160",
        "seconds_per_iteration": {name: {"median": medians[name], "all": per_setting[name],
                                         "worker_niceness": sorted(seen_niceness[name])} for name in SETTINGS},
        "default_over_driver_priority": default / driver,
    }
    for name in SETTINGS:
        logger.info("%-32s %.3f s/it (niceness %s)", name, medians[name], sorted(seen_niceness[name]))
    logger.info("niceness 15 / niceness 0: %.2fx (load average before %s)", default / driver, load_before)
    write_json_result(result, args.out / f"ray_niceness{'_busy' if args.busy else ''}.json")


if __name__ == "__main__":
    main()
