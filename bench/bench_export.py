"""Benchmark: dataset export, per format and end to end.

    .venv/bin/python bench/bench_export.py [--agents 100] [--steps 91] [--lanes 30] [--repeats 30]
        [--store /tmp/demo-copy] [--out bench/results] [--name export]

Per format (``womd``: ``export.womd.encode_scenario``; ``scenarionet``: ``scenario_description`` + pickle;
``parquet``: ``scenario_tables`` + Parquet bytes): the CPU time per scenario of the process (other load on the
machine does not count: ``scenarios_per_s_per_core`` is its inverse), and the bytes per scenario. The scenario is
the export tests' ``make_scenario(agents, steps)`` (cars along +x, a pedestrian, one agent invalid at first, a signal
per step) with ``--lanes`` extra connected 20-point lanes.

With ``--log PATH`` (repeatable; any log the log-source registry detects, e.g. the real samples in
``../shared/data``): the same per-format figures on each window of that log exported unedited.

With ``--store`` (a store the main job mined, e.g. a copy of ``make demo``'s ``artifacts/demo``): the whole
generation of a dataset from that store, ``simsplat export`` of its accepted scenarios into a temporary folder,
with where the time goes: the recorded wall time of each stage that produced them (reconstruction, alignment,
the mining loop's propose / command / edit / render / judge) and of the export, and accepted scenarios per CPU hour
over all of it (wall seconds x the cores the stages ran on, ``--cores``).
Writes ``<out>/<name>.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import logging
import os
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from simsplat_core.export import parquet_tables, scenarionet, womd  # noqa: E402
from simsplat_core.export.record import ExportMapFeature, ExportScenario  # noqa: E402
from tests.simsplat_core.export.conftest import make_scenario  # noqa: E402

logger = logging.getLogger("bench.export")


def bench_scenario(agents: int, steps: int, lanes: int) -> ExportScenario:
    """``make_scenario(agents, steps)`` with ``lanes`` extra 20-point lanes, each connected to the next."""
    base = make_scenario(agents, steps)
    xs = np.linspace(0.0, 100.0, 20)
    extra = tuple(
        ExportMapFeature(1000 + i, "lane", np.stack([xs, np.full_like(xs, 3.5 * i), np.zeros_like(xs)], 1),
                         type="TYPE_SURFACE_STREET", exit_lanes=(1001 + i,), entry_lanes=(999 + i,),
                         left_neighbors=(1001 + i,), speed_limit_mph=35.0)
        for i in range(lanes)
    )
    return dataclasses.replace(base, map_features=base.map_features + extra)


def _parquet_bytes(s: ExportScenario) -> bytes:
    out = io.BytesIO()
    for table in parquet_tables.scenario_tables(s, "train").values():
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink, compression="zstd")
        out.write(sink.getvalue().to_pybytes())
    return out.getvalue()


ENCODERS: dict[str, Callable[[ExportScenario], bytes]] = {
    "womd": womd.encode_scenario,
    "scenarionet": lambda s: scenarionet.to_pickle(scenarionet.scenario_description(s)),
    "parquet": _parquet_bytes,
}


def bench_formats(scenario: ExportScenario, repeats: int) -> dict[str, dict[str, float]]:
    """CPU and wall milliseconds (medians), scenarios per second per core and bytes of each format."""
    out = {}
    for name, encode in ENCODERS.items():
        encode(scenario)  # warm-up (imports, caches)
        cpu, wall = [], []
        data = b""
        for _ in range(repeats):
            c0, w0 = time.process_time(), time.perf_counter()
            data = encode(scenario)
            cpu.append(time.process_time() - c0)
            wall.append(time.perf_counter() - w0)
        cpu_ms = 1000 * statistics.median(cpu)
        out[name] = {"cpu_ms_median": round(cpu_ms, 2), "wall_ms_median": round(1000 * statistics.median(wall), 2),
                     "scenarios_per_s_per_core": round(1000 / cpu_ms, 1), "bytes_per_scenario": len(data)}
        logger.info("%s: %.1f ms CPU, %d bytes", name, cpu_ms, len(data))
    return out


def bench_logs(paths: list[str], repeats: int) -> dict[str, object]:
    """Per-format figures (:func:`bench_formats`) on the first window of each log at ``paths``, exported unedited."""
    from simsplat_core.data.registry import AUTO_SOURCE, load_log
    from simsplat_core.export.from_log import export_unedited

    out: dict[str, object] = {}
    for path in paths:
        log = load_log(AUTO_SOURCE, path)
        scenario = export_unedited([log])[0]
        out[log.seq_id] = {"source": log.source, "tracks": scenario.num_tracks,
                           "map_points": int(sum(len(f.points) for f in scenario.map_features)),
                           "formats": bench_formats(scenario, repeats)}
    return out


def bench_store(store_root: str, cores: int) -> dict[str, object]:
    """Where the time of generating a dataset from ``store_root`` goes (module docstring)."""
    from storage import ArtifactStore
    from storage.edits import edit_run_ids
    from storage.logs import list_logs
    from tasks.eval_all import stage_timings
    from tasks.export import ExportConfig, export_dataset

    store = ArtifactStore(store_root)
    runs = edit_run_ids(store)
    stages: dict[str, float] = {}
    for t in stage_timings(store, list_logs(store), runs):
        stages[t.stage] = stages.get(t.stage, 0.0) + t.seconds
    with tempfile.TemporaryDirectory() as out:
        c0, w0 = time.process_time(), time.perf_counter()
        result = export_dataset(store_root, out, ExportConfig(name="bench"))
        export_wall, export_cpu = time.perf_counter() - w0, time.process_time() - c0
        sizes = {fmt: sum(s.bytes for s in result.shards if s.format == fmt) for fmt in ("womd", "scenarionet",
                                                                                         "parquet")}
    stages["export"] = export_wall
    total = sum(stages.values())
    cpu_hours = total * cores / 3600.0
    return {"runs": runs, "exported": result.written, "left_out": len(result.left_out),
            "stage_wall_s": {k: round(v, 2) for k, v in stages.items()},
            "share": {k: round(v / total, 4) for k, v in stages.items()},
            "export_cpu_s": round(export_cpu, 3), "export_seconds": {k: round(v, 3) for k, v in result.seconds.items()},
            "bytes_by_format": sizes, "cores": cores,
            "exported_per_cpu_hour": round(result.written / cpu_hours, 2) if cpu_hours else None}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--agents", type=int, default=100)
    parser.add_argument("--steps", type=int, default=91)
    parser.add_argument("--lanes", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=30)
    parser.add_argument("--store", help="a store the main job mined (its accepted scenarios are exported)")
    parser.add_argument("--log", action="append", default=[], help="a log to export unedited (repeatable)")
    parser.add_argument("--cores", type=int, default=2, help="cores the store's stages ran on")
    parser.add_argument("--out", default="bench/results")
    parser.add_argument("--name", default="export")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    scenario = bench_scenario(args.agents, args.steps, args.lanes)
    result: dict[str, object] = {
        "agents": args.agents, "steps": args.steps,
        "map_points": int(sum(len(f.points) for f in scenario.map_features)),
        "repeats": args.repeats, "formats": bench_formats(scenario, args.repeats),
        "machine": {"cpu": platform.machine(), "python": platform.python_version(), "cores": os.cpu_count(),
                    "load_1min": round(os.getloadavg()[0], 2)},
    }
    if args.log:
        result["logs"] = bench_logs(args.log, args.repeats)
    if args.store:
        result["store"] = bench_store(args.store, args.cores)
    out = Path(args.out) / f"{args.name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
    logger.info("%s", json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
