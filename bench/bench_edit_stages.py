"""Benchmark: the stages of one language edit (``simsplat edit``) on a stored, aligned scene.

    .venv/bin/python bench/bench_edit_stages.py --store /tmp/demo-copy --seq synth-000000 [--threads 2]
        [--prompt "remove the white van" ...] [--out bench/results]

Give it a COPY of a store (edits are written into it: ``edits/bench-<time>/``) that has an asset bank
(``simsplat assets build``). Per prompt: wall seconds of load (once, shared), parse, apply (ground + place +
plan + validate), render (40 frames x the log's cameras, edited graph, plus the original at the before/after
frames) and write (EXR encoding, pictures, tables), the process CPU seconds of the whole edit, and the bytes
stored. The target is <= 20 s per edit on 2 cores. Outputs ``<out>/edit_stages.json`` and
``<out>/edit_stages.md``. The numbers depend on what else runs on the machine: the CPU seconds say more than
the wall seconds on a shared one.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import time
from pathlib import Path

DEFAULT_PROMPTS = (
    "remove the white van",
    "insert a yellow sedan 12 m ahead of us in our lane",
    "make the green hatchback stop",
    "put a row of orange cones 10 m ahead",
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--store", required=True, help="a COPY of a store with an aligned scene and an asset bank")
    parser.add_argument("--seq", default="synth-000000")
    parser.add_argument("--prompt", action="append", help="prompt (repeatable; default: four typical edits)")
    parser.add_argument("--threads", type=int, default=2, help="torch / numba threads (the target is 2 cores)")
    parser.add_argument("--out", default="bench/results")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)

    started = time.perf_counter()
    from simsplat_core.compute_threads import set_compute_threads
    from storage import ArtifactStore
    from storage.runs import new_run_id
    from tasks.edit import run_edit
    from tasks.stored_edits import load_edit_context

    set_compute_threads(args.threads)
    imports_s = time.perf_counter() - started
    loaded = load_edit_context(ArtifactStore(args.store), args.seq)
    loaded.ctx.engine.embed(["warm up"])  # the text encoder's model load, paid once per process
    warm_s = time.perf_counter() - started
    run_id = new_run_id("bench")
    rows = []
    for prompt in args.prompt or DEFAULT_PROMPTS:
        cpu = time.process_time()
        run = run_edit(args.store, args.seq, prompt, run_id=run_id, loaded=loaded)
        rows.append({"prompt": prompt, "status": run.status, "reason": run.reason,
                     "seconds": {k: round(v, 3) for k, v in run.seconds.items()},
                     "cpu_seconds": round(time.process_time() - cpu, 3), "bytes": run.bytes,
                     "renders": len(loaded.ctx.log.images)})
        print(json.dumps(rows[-1]))
    result = {"store": args.store, "seq": args.seq, "threads": args.threads, "cpus": os.cpu_count(),
              "load_average": os.getloadavg(), "imports_s": round(imports_s, 3),
              "start_to_ready_s": round(warm_s, 3), "edits": rows}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "edit_stages.json").write_text(json.dumps(result, indent=2) + "\n")
    lines = ["| prompt | status | load | parse | apply | render | write | total (s) | CPU s | MB |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        s = r["seconds"]
        lines.append(f"| {r['prompt']} | {r['status']} | " + " | ".join(f"{s.get(k, 0.0):.2f}" for k in (
            "load", "parse", "apply", "render", "write", "total")) + f" | {r['cpu_seconds']:.1f} | "
            f"{r['bytes'].get('total', 0) / 1e6:.2f} |")
    lines.append(f"\n{args.threads} threads; process start to ready (imports, scene, text encoder): "
                 f"{warm_s:.1f} s; load average {result['load_average'][0]:.1f}.")
    (out / "edit_stages.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
