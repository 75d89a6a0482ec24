"""Benchmark: scenario mining (``simsplat eval mining``) on a store's aligned sequences: the Table 5 analogue,
acceptance by category, throughput (accepted scenarios per hour per core) and where the time goes.

    .venv/bin/python bench/bench_mining.py --store /tmp/demo-copy [--per-sequence 3] [--threads 2] [--seq ...]
        [--clients rule] [--out bench/results] [--name mining]

Give it a COPY of a store (the mined scenarios are written into it: ``edits/evalmine-<client>-<time>/``; the
tables into ``runs/bench-mining-<time>/``) that has aligned scenes and an asset bank. Outputs
``<out>/<name>.json`` (the three tables' rows, the run's wall and CPU seconds, threads, load average) and prints
the tables' Markdown. The numbers depend on what else runs on the machine: the CPU seconds say more than the wall
seconds on a shared one.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--store", required=True, help="a COPY of a store with aligned scenes and an asset bank")
    parser.add_argument("--seq", action="append", help="sequence (repeatable; default: every aligned log)")
    parser.add_argument("--per-sequence", type=int, default=3)
    parser.add_argument("--max-attempts", type=int, default=3)
    parser.add_argument("--clients", default="rule", help="comma separated: rule, openai")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=2, help="torch / numba threads (the target is 2 cores)")
    parser.add_argument("--out", default="bench/results")
    parser.add_argument("--name", default="mining", help="result file name (without .json)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)

    started = time.perf_counter()
    cpu = time.process_time()
    from simsplat_core.compute_threads import set_compute_threads
    from storage import ArtifactStore, list_logs
    from storage.language_scenes import list_language_scenes
    from storage.runs import new_run_id, run_dir
    from tasks.mining_eval import evaluate_mining_run

    set_compute_threads(args.threads)
    store = ArtifactStore(args.store)
    seq_ids = args.seq or [s for s in list_logs(store) if list_language_scenes(store, s)]
    out_rel = run_dir(new_run_id("bench-mining"))
    result = evaluate_mining_run.fn(args.store, seq_ids, args.store, out_rel,
                                    clients=[c.strip() for c in args.clients.split(",") if c.strip()],
                                    per_sequence=args.per_sequence, max_attempts=args.max_attempts, seed=args.seed,
                                    cores=args.threads)
    body = {"store": args.store, "sequences": list(result.seq_ids), "per_sequence": args.per_sequence,
            "max_attempts": args.max_attempts, "seed": args.seed, "threads": args.threads, "cpus": os.cpu_count(),
            "load_average": os.getloadavg(), "wall_s": round(time.perf_counter() - started, 1),
            "cpu_s": round(time.process_time() - cpu, 1), "runs": result.runs, "mining": result.mining,
            "accepted_per_cpu_hour": {r["client"]: round(r["accepted"] / ((time.process_time() - cpu) / 3600), 1)
                                      for r in result.mining if r["ran"]},
            "by_category": result.by_category, "stages": result.stages,
            "failed_scenarios": result.failed_scenarios, "tables": result.tables}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{args.name}.json").write_text(json.dumps(body, indent=2, default=float) + "\n")
    for name, uri in result.tables.items():
        md = Path(uri.removeprefix("file://")).with_suffix(".md")
        print(f"## {name}\n\n{md.read_text() if md.exists() else uri}")
    print(f"wall {body['wall_s']} s, CPU {body['cpu_s']} s (accepted per CPU hour {body['accepted_per_cpu_hour']}), "
          f"load average {body['load_average'][0]:.1f}")


if __name__ == "__main__":
    main()
