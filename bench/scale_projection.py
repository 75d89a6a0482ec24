"""Projection: wall time and cost of mining many logs on a Ray cluster of GPU nodes, from measured per-stage costs.

    .venv/bin/python bench/scale_projection.py [--logs 10000] [--nodes 4] [--gpus-per-node 8] [--vcpus-per-node 192]
        [--gpu-reconstruct-s 31.5] [--gpu-hour-usd 3.0] [--stage-costs bench/results/stage_costs.json]
        [--orchestration bench/results/orchestration.json] [--out bench/results] [--name scale_projection]

Inputs (each recorded in the output with where it came from):

* per sequence, the CPU seconds of every stage except reconstruction, measured on this machine by
  ``bench/bench_stage_costs.py`` (default 40-frame sequence; mining K accepted scenarios) or, while its output is
  absent, taken from the benchmarks on record (``world``, ``alignment``, ``mining``, ``export`` JSON files; each
  figure names its file and key in the output). They are assumed to run
  on the nodes' CPU cores at the same CPU cost per core (``--vcpu-speed`` scales that: 0.6 for a hyper-thread that
  gives 60 % of a core here);
* reconstruction on one GPU: ``--gpu-reconstruct-s`` (default: 31.5 s, the default sequence on one H100 with the
  gsplat backend, 900 iterations at 0.024 s each; recorded figure, not measured by this script);
* the orchestration overhead per task (``bench/bench_orchestration.py``, Prefect + Ray, one worker) times the tasks
  per sequence, added to the CPU work; the Prefect API's and Ray's start-up added once;
* the aligner's training, once per run in one process, on ``--aligner-logs`` logs (a sample: on all 10,000 it would
  take longer than the mining) at the CPU seconds per log measured on one log (it grows linearly with the logs:
  ``bench/bench_store_growth.py --train-aligner``);
* the price: ``--gpu-hour-usd`` per GPU-hour for a whole node (CPUs included) — an assumption, not a quote.

The cluster runs GPU and CPU work of different sequences at once (Ray schedules reconstruction tasks on GPUs and the
other stages on CPUs), so the throughput of a node is the smaller of its GPU rate and its CPU rate. Writes
``<out>/<name>.json`` and logs the table the README quotes.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
from pathlib import Path
from typing import Any

logger = logging.getLogger("bench.scale_projection")
from run_info import write_json_result

RESULTS = Path(__file__).resolve().parent / "results"

#: Stages of one sequence that run on CPU cores (reconstruction runs on a GPU; the aligner's training once per run).
CPU_STAGES = ("generate", "align", "mine", "export")
#: Prefect tasks per sequence in a main run: ingest, reconstruct, align, mine (export and bank are one per run).
TASKS_PER_SEQUENCE = 4


def _json(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text())


def recorded_stage_costs(results: Path) -> dict[str, dict[str, Any]]:
    """CPU seconds per default sequence of each CPU stage from the benchmarks on record in ``results`` (each with the
    file and figure it comes from); ``train_aligner`` is per log."""
    world, align, mining, export = (_json(results / f"{n}.json") for n in ("world", "alignment", "mining", "export"))
    accepted = mining["mining"][0]["accepted"] / len(mining["sequences"])  # per sequence
    export_ms = sum(f["cpu_ms_median"] for f in export["formats"].values())
    return {
        "generate": {"cpu_s": round(world["median_generate_s"] + world["median_write_s"], 2),
                     "source": "world.json: median_generate_s + median_write_s (one thread)"},
        "align": {"cpu_s": round(2 * align["times"]["total_s"], 1),
                  "source": "alignment.json: times.total_s x 2 threads (an upper bound of its CPU time)"},
        "mine": {"cpu_s": round(mining["cpu_s"] / len(mining["sequences"]), 1), "accepted": accepted,
                 "source": f"mining.json: cpu_s / sequences (K={mining['per_sequence']} wanted per sequence)"},
        "export": {"cpu_s": round(export_ms / 1e3 * accepted, 3),
                   "source": "export.json: CPU ms per scenario of the three formats x accepted scenarios"},
        "train_aligner": {"cpu_s": round(2 * align["times"]["aligner_training_s"], 1),
                          "source": "alignment.json: aligner_training_s x 2 threads (its training set; per log an "
                                    "upper bound)"},
    }


def measured_stage_costs(path: Path) -> dict[str, dict[str, Any]] | None:
    """The CPU seconds of ``bench/bench_stage_costs.py``'s output at ``path`` (``None`` when absent)."""
    if not path.is_file():
        return None
    stages = _json(path)["stages"]
    return {name: {"cpu_s": stages[name]["cpu_s"], "source": f"{path.name}: stages.{name}.cpu_s",
                   **({"accepted": stages[name]["accepted"]} if "accepted" in stages[name] else {})}
            for name in (*CPU_STAGES, "train_aligner")}


def project(args: argparse.Namespace, stages: dict[str, dict[str, Any]], orchestration: dict[str, Any] | None
            ) -> dict[str, Any]:
    """The projection's figures from per-stage CPU seconds, the orchestration figures and the assumptions in
    ``args``."""
    cpu_per_sequence = sum(stages[s]["cpu_s"] for s in CPU_STAGES) / args.vcpu_speed
    overhead_ms = 0.0
    startup_s = 0.0
    if orchestration is not None:
        per_task = orchestration["overhead"]["trivial"]["overhead_ms_per_task_one_worker"]
        overhead_ms = max(0.0, per_task.get("ray-1", per_task.get("threads-1", 0.0)))
        startup_s = orchestration["prefect_api_start_s"] + orchestration["ray_init_s"].get("seconds", 0.0)
    cpu_per_sequence += TASKS_PER_SEQUENCE * overhead_ms / 1e3
    gpu_rate = args.gpus_per_node / args.gpu_reconstruct_s  # sequences per second per node
    cpu_rate = args.vcpus_per_node / cpu_per_sequence
    node_rate = min(gpu_rate, cpu_rate)
    aligner_logs = min(args.logs, args.aligner_logs)
    aligner_s = stages["train_aligner"]["cpu_s"] / args.vcpu_speed * aligner_logs  # one process, once per run
    wall_s = args.logs / (args.nodes * node_rate) + aligner_s + startup_s
    gpu_hours = args.nodes * args.gpus_per_node * wall_s / 3600
    return {
        "assumptions": {"logs": args.logs, "nodes": args.nodes, "gpus_per_node": args.gpus_per_node,
                        "vcpus_per_node": args.vcpus_per_node, "vcpu_speed": args.vcpu_speed,
                        "gpu_hour_usd": args.gpu_hour_usd, "price_is_an_assumption": True,
                        "gpu_reconstruct_s": args.gpu_reconstruct_s,
                        "gpu_reconstruct_source": "recorded: default sequence on one H100, gsplat backend",
                        "mine_accepted_per_sequence": stages["mine"].get("accepted"),
                        "orchestration_source": str(args.orchestration) if orchestration is not None else None},
        "per_sequence": {"cpu_s": round(cpu_per_sequence, 1), "stages": stages,
                         "orchestration_s": round(TASKS_PER_SEQUENCE * overhead_ms / 1e3, 3),
                         "gpu_s": args.gpu_reconstruct_s},
        "node": {"gpu_bound_sequences_per_hour": round(3600 * gpu_rate), "cpu_bound_sequences_per_hour":
                 round(3600 * cpu_rate), "bound": "gpu" if gpu_rate <= cpu_rate else "cpu",
                 "sequences_per_hour": round(3600 * node_rate)},
        "run": {"mining_h": round(args.logs / (args.nodes * node_rate) / 3600, 2),
                "aligner_training_logs": aligner_logs,
                "aligner_training_s": round(aligner_s), "startup_s": round(startup_s, 1),
                "wall_h": round(wall_s / 3600, 2), "gpu_hours": round(gpu_hours, 1),
                "cost_usd": int(math.ceil(gpu_hours * args.gpu_hour_usd))},
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--logs", type=int, default=10_000)
    parser.add_argument("--nodes", type=int, default=4)
    parser.add_argument("--gpus-per-node", type=int, default=8)
    parser.add_argument("--vcpus-per-node", type=int, default=192)
    parser.add_argument("--vcpu-speed", type=float, default=0.6,
                        help="a node's vCPU relative to one core of the measuring machine")
    parser.add_argument("--gpu-reconstruct-s", type=float, default=31.5)
    parser.add_argument("--aligner-logs", type=int, default=1000,
                        help="logs the motion aligner is trained on (a sample of the store; its cost is per log)")
    parser.add_argument("--gpu-hour-usd", type=float, default=3.0, help="assumed price of one GPU-hour (whole node)")
    parser.add_argument("--stage-costs", type=Path, default=RESULTS / "stage_costs.json")
    parser.add_argument("--orchestration", type=Path, default=RESULTS / "orchestration.json")
    parser.add_argument("--out", default=str(RESULTS))
    parser.add_argument("--name", default="scale_projection")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    stages = measured_stage_costs(args.stage_costs) or recorded_stage_costs(RESULTS)
    orchestration = _json(args.orchestration) if args.orchestration.is_file() else None
    result = project(args, stages, orchestration)
    logger.info("%s", json.dumps(result, indent=2))
    write_json_result(result, Path(args.out) / f"{args.name}.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
