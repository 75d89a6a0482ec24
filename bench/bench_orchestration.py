"""Benchmark: what Prefect and Ray add per task, and pipeline throughput with 1 and 2 Ray workers.

    .venv/bin/python bench/bench_orchestration.py [--trivial 100] [--stage 6] [--throughput-sequences 4]
        [--iterations 30] [--out bench/results] [--name orchestration]

Part 1, overhead per task. The same N tasks run three ways:

* ``direct``: the task's function called in a loop (``task.fn(...)``), no Prefect, no Ray;
* ``threads-W``: a Prefect flow mapping them on ``ThreadPoolTaskRunner(W)`` (``flows.runtime``);
* ``ray-W``: a Prefect flow mapping them on ``flows.runtime.make_task_runner(RunnerKind.ray, W)`` (W Ray CPUs).

Two task kinds: a trivial one (adds 1 to a number) and a real small stage (``tasks.logs.generate_synthetic_log`` of a
tiny world, one seed per task, each mode into its own fresh store). Inside each flow a warm-up of W tasks runs first
(Ray starts its worker processes and imports the task's modules then); the timed span is from the first submit of the
N tasks to the last result. Per-task overhead = (orchestrated - direct) / N with W = 1 (one task at a time in both).
Measured separately: the Prefect API server's start (``flows.runtime.prefect_api``), the flow's start-up (call to
first line of its body: task-runner start, i.e. ``ray.init`` for Ray, and the flow run's registration) and the
warm-up.

Part 2, throughput: ``flows.pipeline.main_flow`` (generate, reconstruct, align, ground-truth benchmark off, mine 1
scenario per sequence) over ``--throughput-sequences`` fresh tiny sequences with 1 and then 2 Ray CPUs, each in a fresh
store; sequences per hour = sequences / flow wall time (Prefect API start excluded: one per run, shared by all).

Every figure carries the 1-minute load average before and after it: this machine's 2 cores are shared, so compare
figures of one run with each other (ratios), not with other runs. Writes ``<out>/<name>.json``.
"""

from __future__ import annotations

import argparse
import functools
import logging
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
os.environ.setdefault("RAY_AUTH_MODE", "disabled")
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")

from prefect import flow, task  # noqa: E402
from prefect.cache_policies import NO_CACHE  # noqa: E402
from run_info import load_average, machine_info, write_json_result  # noqa: E402

from flows.runtime import RunnerKind, make_task_runner, prefect_api, shutdown_ray  # noqa: E402
from simsplat_core.world import WorldConfig  # noqa: E402
from tasks.logs import generate_synthetic_log  # noqa: E402

logger = logging.getLogger("bench.orchestration")

#: The real small stage's world: a log of a few frames at a small size (about 0.1-0.3 s to generate here).
TINY_WORLD = WorldConfig(num_frames=8, width=64, height=48)


@task(name="bench-trivial", cache_policy=NO_CACHE)
def trivial(value: int) -> int:
    """The smallest task there is: ``value + 1``."""
    return value + 1


def _trivial_args(i: int, _store: str) -> tuple:
    return (i,)


def _stage_args(i: int, store: str) -> tuple:
    return (store, 1000 + i, TINY_WORLD)


#: Task kinds measured: (task, arguments of the i-th call given a store root).
KINDS: dict[str, tuple[Any, Callable[[int, str], tuple]]] = {
    "trivial": (trivial, _trivial_args),
    "generate-tiny-log": (generate_synthetic_log, _stage_args),
}


@flow(name="bench-orchestration")
def mapped_flow(kind: str, count: int, warmup: int, store: str, called_at: float) -> dict[str, float]:
    """Run ``warmup`` then ``count`` tasks of ``kind`` on this flow's task runner; the spans it measured (s)."""
    body_start = time.perf_counter()
    fn, args = KINDS[kind]
    started = time.perf_counter()
    [f.result() for f in [fn.submit(*args(-1 - i, store)) for i in range(warmup)]]
    warm = time.perf_counter()
    futures = [fn.submit(*args(i, store)) for i in range(count)]
    for future in futures:
        future.result()
    done = time.perf_counter()
    return {"startup_s": body_start - called_at, "warmup_s": warm - started, "tasks_s": done - warm}


def run_direct(kind: str, count: int, store: str) -> float:
    """Seconds to call ``kind``'s function ``count`` times in this process, without Prefect or Ray."""
    fn, args = KINDS[kind]
    fn.fn(*args(-1, store))  # same warm-up as the flows: imports and first-call caches
    started = time.perf_counter()
    for i in range(count):
        fn.fn(*args(i, store))
    return time.perf_counter() - started


def retrying_ray_start(call: Callable[[], Any], attempts: int = 3) -> tuple[Any, int]:
    """``call()``, called again (up to ``attempts`` times) when Ray's node fails to start: Ray gives its raylet a fixed
    30 s to register, which a heavily loaded machine can miss. The result and the attempts it took."""
    for attempt in range(1, attempts + 1):
        try:
            return call(), attempt
        except Exception as exc:
            shutdown_ray()
            if "timed out during startup" not in str(exc) or attempt == attempts:
                raise
            logger.warning("Ray did not start (attempt %d of %d): %s", attempt, attempts, exc)
    raise AssertionError("unreachable")


def run_orchestrated(kind: str, count: int, runner: RunnerKind, workers: int, store: str) -> dict[str, float]:
    """The spans of ``mapped_flow`` on ``runner`` with ``workers``, plus the flow call's whole wall time."""

    def once() -> dict[str, float]:
        called = time.perf_counter()
        spans = mapped_flow.with_options(task_runner=make_task_runner(runner, workers))(kind, count, workers, store,
                                                                                     called)
        spans["flow_total_s"] = time.perf_counter() - called
        return spans

    spans, attempts = retrying_ray_start(once)
    shutdown_ray()
    return spans | {"ray_start_attempts": attempts}


def measure_overhead(kind: str, count: int, scratch: Path) -> dict[str, Any]:
    """Direct, threads-1/2 and ray-1/2 runs of ``count`` ``kind`` tasks, with per-task overheads against direct."""
    modes: dict[str, Any] = {}

    def fresh(name: str) -> str:
        path = scratch / f"{kind}-{name}"
        shutil.rmtree(path, ignore_errors=True)
        return str(path)

    load = load_average()
    modes["direct"] = {"tasks_s": run_direct(kind, count, fresh("direct")),
                       "load_before": load, "load_after": load_average()}
    logger.info("%s: direct %d calls in %.3f s", kind, count, modes["direct"]["tasks_s"])
    for runner in (RunnerKind.threads, RunnerKind.ray):
        for workers in (1, 2):
            name = f"{runner.value}-{workers}"
            load = load_average()
            try:
                spans = run_orchestrated(kind, count, runner, workers, fresh(name))
            except Exception as exc:  # Ray that never starts on an overloaded machine: recorded, the rest measured
                logger.error("%s: %s failed: %s", kind, name, exc)
                modes[name] = {"error": f"{type(exc).__name__}: {exc}", "load_before": load}
                continue
            modes[name] = {k: round(v, 4) for k, v in spans.items()} | {"load_before": load,
                                                                        "load_after": load_average()}
            logger.info("%s: %s start-up %.2f s, warm-up %.2f s, %d tasks %.3f s", kind, name, spans["startup_s"],
                        spans["warmup_s"], count, spans["tasks_s"])
    direct = modes["direct"]["tasks_s"]
    overhead = {name: round(1e3 * (m["tasks_s"] - direct) / count, 2) for name, m in modes.items()
                if name.endswith("-1") and "tasks_s" in m}
    return {"tasks": count, "modes": modes, "direct_ms_per_task": round(1e3 * direct / count, 2),
            "overhead_ms_per_task_one_worker": overhead,
            "speedup_two_workers": {r: round(modes[f"{r}-1"]["tasks_s"] / modes[f"{r}-2"]["tasks_s"], 2)
                                    for r in ("threads", "ray")
                                    if "tasks_s" in modes[f"{r}-1"] and "tasks_s" in modes[f"{r}-2"]}}


def measure_throughput(sequences: int, iterations: int, scratch: Path) -> dict[str, Any]:
    """``main_flow`` over ``sequences`` fresh tiny sequences with 1 and 2 Ray CPUs; sequences per hour each."""
    from flows.pipeline import MiningPlan, main_flow, reconstruction_config

    world = WorldConfig(num_frames=12, width=96, height=64)
    rows: dict[str, Any] = {}
    for workers in (1, 2):
        store = scratch / f"throughput-{workers}"
        shutil.rmtree(store, ignore_errors=True)
        load = load_average()
        started = time.perf_counter()
        flow_call = functools.partial(main_flow.with_options(task_runner=make_task_runner(RunnerKind.ray, workers)),
                                      str(store), list(range(sequences)), world, reconstruction_config(iterations),
                                      evaluate=False, mining=MiningPlan(1))
        result, _ = retrying_ray_start(flow_call)
        wall = time.perf_counter() - started
        shutdown_ray()
        rows[f"ray-{workers}"] = {"wall_s": round(wall, 2), "sequences_per_hour": round(sequences * 3600 / wall, 1),
                                  "accepted": sum(m.accepted for m in result.mining), "load_before": load,
                                  "load_after": load_average()}
        logger.info("throughput, %d Ray CPU(s): %d sequences in %.1f s = %.1f sequences/h", workers, sequences, wall,
                    rows[f"ray-{workers}"]["sequences_per_hour"])
    rows["speedup_two_workers"] = round(rows["ray-1"]["wall_s"] / rows["ray-2"]["wall_s"], 2)
    rows["setup"] = {"sequences": sequences, "frames": world.num_frames, "size": [world.width, world.height],
                     "iterations": iterations, "mine_per_sequence": 1, "grounding_benchmark": False}
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trivial", type=int, default=100, help="trivial tasks per mode")
    parser.add_argument("--stage", type=int, default=6, help="tiny-log generation tasks per mode (0: skip)")
    parser.add_argument("--throughput-sequences", type=int, default=4, help="sequences per throughput run (0: skip)")
    parser.add_argument("--iterations", type=int, default=30, help="reconstruction iterations in the throughput runs")
    parser.add_argument("--out", default="bench/results")
    parser.add_argument("--name", default="orchestration")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s", force=True)
    scratch = Path(tempfile.mkdtemp(prefix="bench-orchestration-"))
    result: dict[str, Any] = {"machine": machine_info() | {"load_at_start": load_average()}}
    try:
        load = load_average()
        started = time.perf_counter()
        with prefect_api(timeout_s=600) as url:  # a loaded machine starts it slowly
            result["prefect_api_start_s"] = round(time.perf_counter() - started, 2)
            result["prefect_api_start_load"] = load
            logger.info("Prefect API %s started in %.1f s", url, result["prefect_api_start_s"])
            import ray

            load = load_average()
            started = time.perf_counter()
            try:
                _, attempts = retrying_ray_start(lambda: ray.init(num_cpus=2, include_dashboard=False))
                result["ray_init_s"] = {"seconds": round(time.perf_counter() - started, 2), "load_before": load,
                                        "attempts": attempts}
            except Exception as exc:  # recorded; the thread-runner figures are still measured
                result["ray_init_s"] = {"error": f"{type(exc).__name__}: {exc}", "load_before": load}
            shutdown_ray()
            result["overhead"] = {"trivial": measure_overhead("trivial", args.trivial, scratch)}
            if args.stage:
                result["overhead"]["generate-tiny-log"] = measure_overhead("generate-tiny-log", args.stage, scratch)
            if args.throughput_sequences:
                result["throughput"] = measure_throughput(args.throughput_sequences, args.iterations, scratch)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    result["machine"]["load_at_end"] = load_average()
    write_json_result(result, Path(args.out) / f"{args.name}.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
