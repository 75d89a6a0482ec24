"""Benchmark: ``ExportScenario`` -> WOMD ``Scenario`` bytes (``simsplat_core.export.womd.encode_scenario``).

    .venv/bin/python bench/bench_womd_export.py [--agents 100] [--steps 91] [--lanes 30] [--repeats 50]

The scenario is the export tests' ``make_scenario(agents, steps)`` (cars along +x, one pedestrian, one agent
invalid for its first steps, one signal per step) with ``--lanes`` extra 20-point lanes (about 600 lane points with
the defaults, plus the fixture's own map). Reported per scenario: the process CPU time (the machine's other load
does not count: ``scenarios_per_s_per_core`` is its inverse), the wall time, the serialized bytes and what one
TFRecord shard record adds. Writes ``bench/results/womd_export.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from simsplat_core.export.record import ExportMapFeature, ExportScenario  # noqa: E402
from simsplat_core.export.womd import encode_scenario, encode_shard  # noqa: E402
from tests.simsplat_core.export.conftest import make_scenario  # noqa: E402

logger = logging.getLogger("bench.womd_export")


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--agents", type=int, default=100)
    parser.add_argument("--steps", type=int, default=91)
    parser.add_argument("--lanes", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "womd_export.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    scenario = bench_scenario(args.agents, args.steps, args.lanes)
    data = encode_scenario(scenario)  # warm-up
    cpu, wall = [], []
    for _ in range(args.repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        encode_scenario(scenario)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    cpu_ms = 1e3 * statistics.median(cpu)
    result = {
        "agents": args.agents,
        "steps": args.steps,
        "map_points": int(sum(len(f.points) for f in scenario.map_features)),
        "repeats": args.repeats,
        "cpu_ms_median": round(cpu_ms, 2),
        "wall_ms_median": round(1e3 * statistics.median(wall), 2),
        "scenarios_per_s_per_core": round(1e3 / cpu_ms, 1),
        "bytes_per_scenario": len(data),
        "tfrecord_bytes_per_scenario": len(encode_shard([scenario])),
        "machine": {"cpu": platform.machine(), "python": platform.python_version(), "cores": os.cpu_count(),
                    "load_1min": round(os.getloadavg()[0], 2)},
    }
    logger.info("%s", json.dumps(result, indent=2))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
