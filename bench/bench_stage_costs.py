"""Benchmark: what each stage costs per sequence on this machine, called directly (no Prefect, no Ray).

    .venv/bin/python bench/bench_stage_costs.py [--seed 0] [--iterations 90] [--mine 3] [--threads 2]
        [--out bench/results] [--name stage_costs]

One default sequence (``WorldConfig()``: 40 frames, 3 cameras at 240x160) goes through every stage of the main job in
one process, each stage's task function called as ``task.fn`` into a fresh store: generate (ingest), reconstruct
(``--iterations``, then projected to the default iteration count), train the motion aligner on the one log, align the
scene, build the asset bank, mine ``--mine`` accepted scenarios with the rule-based client, export them. Per stage:
wall and CPU time, and the 1-minute load average before and after it (the machine is shared: a loaded machine
stretches wall time, CPU time less so).

Reconstruction projection to the default ``ReconstructionConfig().iterations``: its time outside the training loop
(initialisation, test-frame evaluation, writing) plus seconds per iteration x iterations. A reduced run stops before
densification (which starts at iteration 200 and grows the Gaussian count to about 150,000 by iteration 900), so its
seconds per iteration are those of the initial Gaussians: the projection is a lower bound; the recorded full run
(``bench/results/reconstruct.json``) is quoted beside it. Writes ``<out>/<name>.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from run_info import load_average, machine_info, write_json_result  # noqa: E402

from simsplat_core.compute_threads import set_compute_threads  # noqa: E402
from simsplat_core.scene import ReconstructionConfig  # noqa: E402
from simsplat_core.world import WorldConfig, default_seq_id  # noqa: E402
from tasks.align import align_scene, train_motion_aligner  # noqa: E402
from tasks.assets import build_asset_bank  # noqa: E402
from tasks.export import ExportConfig, export_dataset_task  # noqa: E402
from tasks.export_inputs import ExportFilters  # noqa: E402
from tasks.logs import generate_synthetic_log  # noqa: E402
from tasks.mine import mine_sequence_task  # noqa: E402
from tasks.reconstruct import reconstruct_scene  # noqa: E402

logger = logging.getLogger("bench.stage_costs")
RESULTS = Path(__file__).resolve().parent / "results"


def timed(stages: dict[str, Any], name: str, call: Callable[[], Any]) -> Any:
    """Run ``call``, record its wall and CPU seconds and the load around it under ``stages[name]``."""
    load = load_average()
    wall, cpu = time.perf_counter(), time.process_time()
    result = call()
    stages[name] = {"wall_s": round(time.perf_counter() - wall, 2), "cpu_s": round(time.process_time() - cpu, 2),
                    "load_before": load, "load_after": load_average()}
    logger.info("%-16s %7.1f s wall %7.1f s CPU (load %s -> %s)", name, stages[name]["wall_s"], stages[name]["cpu_s"],
                load[:1], stages[name]["load_after"][:1])
    return result


def reconstruction_projection(metrics: dict[str, float], wall_s: float, iterations: int) -> dict[str, Any]:
    """The reduced run's time projected to ``iterations``: outside-the-loop time + seconds per iteration x it."""
    outside = wall_s - metrics["train_time_s"]
    per_iteration = metrics["seconds_per_iteration"]
    recorded = json.loads((RESULTS / "reconstruct.json").read_text())["results"] if (
        RESULTS / "reconstruct.json").is_file() else {}
    return {"iterations": iterations, "outside_loop_s": round(outside, 2),
            "seconds_per_iteration": round(per_iteration, 4),
            "projected_wall_s": round(outside + per_iteration * iterations, 1),
            "recorded_full_run": {k: recorded.get(k) for k in ("wall_time_s", "seconds_per_iteration",
                                                                "num_gaussians")},
            "note": "lower bound: the reduced run stops before densification grows the Gaussian count"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=90, help="reconstruction iterations actually run")
    parser.add_argument("--mine", type=int, default=3, help="accepted scenarios to mine")
    parser.add_argument("--threads", type=int, default=2, help="torch/numba threads")
    parser.add_argument("--out", default=str(RESULTS))
    parser.add_argument("--name", default="stage_costs")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s", force=True)
    set_compute_threads(args.threads)
    root = tempfile.mkdtemp(prefix="bench-stage-costs-")
    seq_id = default_seq_id(args.seed)
    default_iterations = ReconstructionConfig().iterations
    config = dataclasses.replace(ReconstructionConfig(), iterations=args.iterations, num_threads=args.threads)
    stages: dict[str, Any] = {}
    try:
        timed(stages, "generate", lambda: generate_synthetic_log.fn(root, args.seed, WorldConfig()))
        scene = timed(stages, "reconstruct", lambda: reconstruct_scene.fn(root, seq_id, config))
        aligner = timed(stages, "train_aligner", lambda: train_motion_aligner.fn(root, [seq_id]))
        timed(stages, "align", lambda: align_scene.fn(root, seq_id, scene.scene_hash, aligner.model_hash,
                                                      threads=args.threads))
        timed(stages, "asset_bank", lambda: build_asset_bank.fn(root))
        mined = timed(stages, "mine", lambda: mine_sequence_task.fn(root, seq_id, "bench-stage-costs",
                                                                    per_sequence=args.mine, threads=args.threads))
        export = ExportConfig(name="bench", filters=ExportFilters(include="accepted", runs=("bench-stage-costs",)))
        exported = timed(stages, "export", lambda: export_dataset_task.fn(root, None, export))
        stages["reconstruct"]["projection"] = reconstruction_projection(scene.metrics, stages["reconstruct"]["wall_s"],
                                                                        default_iterations)
        stages["mine"]["accepted"], stages["mine"]["attempts"] = mined.accepted, mined.attempts
        stages["export"]["scenarios"] = exported.written
    finally:
        shutil.rmtree(root, ignore_errors=True)
    per_sequence = sum(s["wall_s"] for name, s in stages.items() if name != "reconstruct")
    result = {"machine": machine_info() | {"threads": args.threads},
              "sequence": {"seed": args.seed, "world": dataclasses.asdict(WorldConfig())},
              "iterations_run": args.iterations, "default_iterations": default_iterations, "stages": stages,
              "per_sequence_wall_s_with_projected_reconstruction": round(
                  per_sequence + stages["reconstruct"]["projection"]["projected_wall_s"], 1)}
    write_json_result(result, Path(args.out) / f"{args.name}.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
