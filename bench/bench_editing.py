"""Benchmark: language editing on the stored synthetic scenes -- task completion (SIMSplat Table 3), infeasible
prompts refused, edit fidelity, and the time of one full edit per category.

    .venv/bin/python bench/bench_editing.py --store DIR [--per-category 30] [--methods ours,chatsim-like,...]
                                            [--skip-eval] [--out bench/results/editing.json]

``DIR`` holds reconstructed, language-aligned synthetic sequences and an asset bank (``simsplat assets build``);
it is only read (the evaluation's tables go to ``--eval-out``, default a temporary directory).

1. **One edit per category** (scene of the first sequence, the first prompt of each category that ``ours``
   completes in the evaluation's prompt set): parse, ground + apply + validate (``apply_edit``), and render
   every frame and camera of the edited graph with node ids (``editing.renders.render_frames``, 40 frames x 3
   cameras at 240x160), timed separately; ``--repeats`` runs, the median reported, and the first run of the
   prompt (its phrases not yet in the text encoder's cache) in full. Torch uses ``--threads`` threads (the
   target is <= 20 s on 2 cores).
   Then the prompts of ``LOOK_PROMPTS`` (inserts asked in a colour, which the look check renders and, at worst,
   re-applies with another asset: ``editing.assets.look_check``) are timed the same way.
2. **The evaluation** (``tasks.editing_eval.evaluate_editing_run``): completion per (method, category),
   infeasible prompts refused, fidelity per category next to the unedited test PSNR, failures grouped by
   reason.

The machine may be shared: timings are indicative (the 1-minute load average is recorded). Writes
``bench/results/editing.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import re
import statistics
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import torch  # noqa: E402

from simsplat_core.editing.apply import Editor, apply_edit  # noqa: E402
from simsplat_core.editing.renders import render_frames  # noqa: E402
from simsplat_core.editing.result import EditRefused  # noqa: E402
from simsplat_core.eval.editing.prompts import CATEGORIES, PromptConfig, build_prompt_set  # noqa: E402
from simsplat_core.eval.editing.truth import SceneTruth  # noqa: E402
from simsplat_core.language.grounding.engine import QueryEngine  # noqa: E402
from simsplat_core.language.text import default_text_encoder  # noqa: E402
from storage import ArtifactStore, list_logs, read_scene_log  # noqa: E402
from storage.assets import read_asset_bank  # noqa: E402
from storage.language_scenes import list_language_scenes  # noqa: E402
from tasks.stored_edits import load_edit_context  # noqa: E402

logger = logging.getLogger("bench.editing")

#: Inserts asked in white / silver / gray / black: the look check renders the edited scene for them.
LOOK_PROMPTS = ("put a white car in our lane 20 m ahead", "add a silver van 12 m ahead of us in our lane",
                "add a black SUV in the left lane 15 m ahead", "place a white pickup 10 m ahead of us",
                "add a blue hatchback in our lane 15 m ahead", "put a yellow van 20 m ahead in the left lane")


def time_one_edit_per_category(store_root: str, seq_id: str, repeats: int) -> dict:
    """Median seconds of parse / apply / render / total of one edit of each category (module docstring)."""
    store = ArtifactStore(store_root)
    engine = QueryEngine(default_text_encoder())
    loaded = load_edit_context(store, seq_id, engine=engine, bank=read_asset_bank(store))
    ctx = loaded.ctx
    truth = SceneTruth.from_log(read_scene_log(store, seq_id), {n.object_id: n.node_id for n in ctx.graph.object_nodes})
    prompts = build_prompt_set([truth], PromptConfig(per_category=12, infeasible=0))
    editor = Editor(ctx)
    editor.parse("remove the white van")  # warm the parser's and the encoder's one-off set-up
    out = {}
    for category in CATEGORIES:
        for prompt in (p for p in prompts if p.category == category):
            timed = _time_prompt(editor, prompt.text, repeats)
            if timed is None:
                continue
            out[category] = timed
            break
        else:
            out[category] = {"prompt": "", "error": "no prompt of this category was carried out"}
            logger.warning("%s: no prompt carried out, nothing timed", category)
    for k, text in enumerate(LOOK_PROMPTS):
        timed = _time_prompt(editor, text, repeats)
        if timed is not None:
            out[f"look_check_{k}"] = timed
    return out


def _time_prompt(editor: Editor, text: str, repeats: int) -> dict | None:
    """Timings of one prompt (module docstring, point 1), ``None`` when it is refused."""
    ctx = editor.ctx
    t0 = time.perf_counter()
    try:
        first = editor.edit(text)
    except EditRefused:
        return None
    list(render_frames(first.graph, ctx.log))
    cold_s = time.perf_counter() - t0  # the text's phrases not yet in the encoder's cache
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        program = editor.parse(text)
        t1 = time.perf_counter()
        edited = apply_edit(ctx, program)
        t2 = time.perf_counter()
        frames = list(render_frames(edited.graph, ctx.log))
        t3 = time.perf_counter()
        runs.append((t1 - t0, t2 - t1, t3 - t2, t3 - t0))
    parse_s, apply_s, render_s, total_s = (statistics.median(r[k] for r in runs) for k in range(4))
    logger.info("total %6.2f s (parse %.2f, ground+apply+validate %.2f, render %.2f; first run %.2f s): %s",
                total_s, parse_s, apply_s, render_s, cold_s, text)
    return {"prompt": text, "parse_s": round(parse_s, 3), "apply_s": round(apply_s, 3),
            "render_s": round(render_s, 3), "total_s": round(total_s, 3), "cold_total_s": round(cold_s, 3),
            "summary": "; ".join(o.summary for o in first.outcomes),
            "frames": len(frames), "cameras": len(frames[0].cameras) if frames else 0}


def failure_groups(outcomes_uri: str, method: str = "ours") -> dict[str, list[str]]:
    """The failed prompts of ``method`` grouped by the first failed condition of their reason."""
    import pyarrow.parquet as pq

    rows = [r for r in pq.read_table(outcomes_uri).to_pylist() if r["method"] == method and not r["completed"]]
    groups: dict[str, list[str]] = {}
    for r in rows:
        first = r["reason"].split(" | ")[0].split("; ")[0] if not r["refusal"] else f"refused ({r['refusal']})"
        key = re.sub(r"[-\d.]+", "#", first)[:90]
        groups.setdefault(key, []).append(f"[{r['category']}] {r['text']} -> {r['reason'][:240]}")
    return dict(sorted(groups.items(), key=lambda kv: -len(kv[1])))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--store", required=True)
    parser.add_argument("--seq", action="append", help="sequence (repeatable; default: every aligned log)")
    parser.add_argument("--per-category", type=int, default=30)
    parser.add_argument("--infeasible", type=int, default=20)
    parser.add_argument("--methods", default="ours,chatsim-like,omnire-like")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--skip-eval", action="store_true", help="time one edit per category only")
    parser.add_argument("--skip-timing", action="store_true", help="run the evaluation only")
    parser.add_argument("--eval-out", default="", help="run directory of the evaluation's tables (default: temp)")
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "editing.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    torch.set_num_threads(args.threads)
    store = ArtifactStore(args.store)
    seq_ids = args.seq or [s for s in list_logs(store) if list_language_scenes(store, s)]
    result: dict = {"store": args.store, "sequences": seq_ids, "threads": args.threads}
    if not args.skip_timing:
        result["one_edit"] = time_one_edit_per_category(args.store, seq_ids[0], args.repeats)
        totals = [max(v["total_s"], v["cold_total_s"]) for v in result["one_edit"].values() if "total_s" in v]
        result["one_edit_max_s"] = max(totals) if totals else None
    if not args.skip_eval:
        from tasks.editing_eval import evaluate_editing_run

        out_dir = args.eval_out or tempfile.mkdtemp(prefix="bench-editing-")
        started = time.perf_counter()
        ev = evaluate_editing_run.fn(args.store, seq_ids, out_dir, per_category=args.per_category,
                                     infeasible=args.infeasible, methods=args.methods.split(","))
        result["evaluation"] = {"prompts": ev.prompts, "completion": ev.completion, "refused": ev.refused,
                                "fidelity": ev.fidelity, "edit_seconds": ev.edit_seconds, "tables": ev.tables,
                                "seconds": round(time.perf_counter() - started, 1)}
        result["failures_ours"] = failure_groups(ev.tables["editing_outcomes"])
        for method, per in ev.completion.items():
            logger.info("%-13s %s | total %.3f | infeasible refused %.3f", method,
                        " ".join(f"{c} {per[c]:.2f}" for c in CATEGORIES), per["total"], ev.refused[method])
        for method, per in ev.fidelity.items():
            logger.info("%-13s fidelity PSNR %s | unedited %.2f", method,
                        " ".join(f"{c} {per[c]['psnr']:.2f}" for c in (*CATEGORIES, "total")),
                        per["total"]["psnr_unedited"])
        counts = Counter({k: len(v) for k, v in result["failures_ours"].items()})
        for reason, n in counts.most_common(12):
            logger.info("%3d x %s", n, reason)
    result["machine"] = {"cpu": platform.machine(), "cores": os.cpu_count(), "python": platform.python_version(),
                         "load_average_1m_at_end": round(os.getloadavg()[0], 2)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2, default=float) + "\n")
    logger.info("-> %s", args.out)


if __name__ == "__main__":
    main()
