"""Projection: wall time and cost of mining many logs on a Ray cluster of GPU nodes, from measured per-stage costs.

    .venv/bin/python bench/scale_projection.py [--logs 10000] [--nodes 4] [--gpus-per-node 8] [--vcpus-per-node 192]
        [--gpu-reconstruct-s 31.5] [--gpu-hour-usd 3.0] [--stage-costs bench/results/stage_costs.json]
        [--orchestration bench/results/orchestration.json] [--out bench/results] [--name scale_projection]

Inputs (each recorded in the output with where it came from):

* per sequence, the CPU seconds of every stage except reconstruction, measured on this machine by
  ``bench/bench_stage_costs.py`` (default 40-frame sequence; mining K accepted scenarios). They are assumed to run
  on the nodes' CPU cores at the same CPU cost per core (``--vcpu-speed`` scales that: 0.6 for a hyper-thread that
  gives 60 % of a core here);
* reconstruction on one GPU: ``--gpu-reconstruct-s`` (default: 31.5 s, the default sequence on one H100 with the
  gsplat backend, 900 iterations at 0.024 s each; recorded figure, not measured by this script);
* the orchestration overhead per task (``bench/bench_orchestration.py``, Prefect + Ray, one worker) times the tasks
  per sequence, added to the CPU work; the Prefect API's and Ray's start-up added once;
* the aligner's training, once per run over all logs, at the CPU seconds per log that ``bench_stage_costs`` measured
  on one log (it grows linearly with the logs: ``bench/bench_store_growth.py --train-aligner``);
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
RESULTS = Path(__file__).resolve().parent / "results"

#: Stages of one sequence that run on CPU cores (reconstruction runs on a GPU; the aligner's training once per run).
CPU_STAGES = ("generate", "align", "mine", "export")
#: Prefect tasks per sequence in a main run: ingest, reconstruct, align, mine (export and bank are one per run).
TASKS_PER_SEQUENCE = 4


def project(args: argparse.Namespace, stage_costs: dict[str, Any], orchestration: dict[str, Any] | None
            ) -> dict[str, Any]:
    """The projection's figures from the measured inputs and the cluster assumptions in ``args``."""
    stages = stage_costs["stages"]
    cpu_per_sequence = sum(stages[s]["cpu_s"] for s in CPU_STAGES) / args.vcpu_speed
    overhead_ms = 0.0
    startup_s = 0.0
    if orchestration is not None:
        overhead_ms = max(0.0, orchestration["overhead"]["trivial"]["overhead_ms_per_task_one_worker"]["ray-1"])
        startup_s = orchestration["prefect_api_start_s"] + orchestration["ray_init_s"]["seconds"]
    cpu_per_sequence += TASKS_PER_SEQUENCE * overhead_ms / 1e3
    gpu_rate = args.gpus_per_node / args.gpu_reconstruct_s  # sequences per second per node
    cpu_rate = args.vcpus_per_node / cpu_per_sequence
    node_rate = min(gpu_rate, cpu_rate)
    aligner_s = stages["train_aligner"]["cpu_s"] / args.vcpu_speed * args.logs  # one process, once per run
    wall_s = args.logs / (args.nodes * node_rate) + aligner_s + startup_s
    gpu_hours = args.nodes * args.gpus_per_node * wall_s / 3600
    return {
        "assumptions": {"logs": args.logs, "nodes": args.nodes, "gpus_per_node": args.gpus_per_node,
                        "vcpus_per_node": args.vcpus_per_node, "vcpu_speed": args.vcpu_speed,
                        "gpu_hour_usd": args.gpu_hour_usd, "price_is_an_assumption": True,
                        "gpu_reconstruct_s": args.gpu_reconstruct_s,
                        "gpu_reconstruct_source": "recorded: default sequence on one H100, gsplat backend",
                        "cpu_stages_source": str(args.stage_costs),
                        "mine_per_sequence": stages["mine"].get("accepted"),
                        "orchestration_source": str(args.orchestration) if orchestration is not None else None},
        "per_sequence": {"cpu_s": round(cpu_per_sequence, 1),
                         "cpu_s_by_stage": {s: stages[s]["cpu_s"] for s in CPU_STAGES},
                         "orchestration_s": round(TASKS_PER_SEQUENCE * overhead_ms / 1e3, 3),
                         "gpu_s": args.gpu_reconstruct_s},
        "node": {"gpu_bound_sequences_per_hour": round(3600 * gpu_rate), "cpu_bound_sequences_per_hour":
                 round(3600 * cpu_rate), "bound": "gpu" if gpu_rate <= cpu_rate else "cpu",
                 "sequences_per_hour": round(3600 * node_rate)},
        "run": {"aligner_training_s": round(aligner_s), "startup_s": round(startup_s, 1),
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
    parser.add_argument("--gpu-hour-usd", type=float, default=3.0, help="assumed price of one GPU-hour (whole node)")
    parser.add_argument("--stage-costs", type=Path, default=RESULTS / "stage_costs.json")
    parser.add_argument("--orchestration", type=Path, default=RESULTS / "orchestration.json")
    parser.add_argument("--out", default=str(RESULTS))
    parser.add_argument("--name", default="scale_projection")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    stage_costs = json.loads(args.stage_costs.read_text())
    orchestration = json.loads(args.orchestration.read_text()) if args.orchestration.is_file() else None
    result = project(args, stage_costs, orchestration)
    logger.info("%s", json.dumps(result, indent=2))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{args.name}.json").write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
