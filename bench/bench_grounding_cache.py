"""Benchmark: the grounding benchmark stage of a run over a store of n logs, evaluated afresh against a run that adds
one log to a store whose other logs were evaluated before (``storage.grounding_outcomes``).

    .venv/bin/python bench/bench_grounding_cache.py [--logs 10] [--frames 20] [--width 120] [--height 80]

The store holds n synthetic logs, each with a ground-truth language scene (node-id maps from the log's instance
masks, written by ``tests/small_store.py``; nothing is trained, the benchmark's work is the same). Three timings:
all n from scratch, the same n again (every answer kept), and n + 1 after one more log landed. Checks that
the n + 1 tables equal a fresh evaluation of the n + 1 logs (timings aside). Writes
``bench/results/grounding_cache.json``.
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
import time
from pathlib import Path

from run_info import load_average, machine_info, write_json_result

from simsplat_core.eval.grounding.tables import GROUNDING_SPEC, OUTCOMES_SPEC
from simsplat_core.world import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import ArtifactStore
from storage.grounding_outcomes import CACHE_DIR
from storage.runs import read_run_table
from tasks.grounding_eval import evaluate_grounding_run

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root: the tests' store writer
from tests.small_store import write_small_store  # noqa: E402

logger = logging.getLogger("bench.grounding_cache")
MODEL_HASH = "be9c" + "0" * 60


def _add_log(root: str, seed: int, config: WorldConfig) -> str:
    """A synthetic log with its initial graph as the scene and a ground-truth language scene; returns its id."""
    log = generate_log(seed, config)
    write_small_store(root, log, scene_hash=f"{seed:064x}", model_hash=MODEL_HASH, language_hash=f"{seed + 1:064x}")
    return log.seq_id


def _timed_run(root: str, seq_ids: list[str], name: str) -> tuple[float, list[str]]:
    started = time.perf_counter()
    evaluate_grounding_run.fn(root, seq_ids, root, f"runs/{name}")
    seconds = time.perf_counter() - started
    evaluated = ArtifactStore(root).read_json(f"runs/{name}/manifest.json")["sequences_evaluated_this_run"]
    logger.info("%-22s %3d logs, %3d evaluated: %.1f s", name, len(seq_ids), len(evaluated), seconds)
    return seconds, evaluated


def _tables(root: str, name: str):
    store = ArtifactStore(root)
    return [read_run_table(store, f"runs/{name}", spec).drop_columns(["seconds"] if spec is OUTCOMES_SPEC else [])
            for spec in (GROUNDING_SPEC, OUTCOMES_SPEC)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--logs", type=int, default=10)
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--width", type=int, default=120)
    parser.add_argument("--height", type=int, default=80)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s", force=True)
    config = WorldConfig(num_frames=args.frames, width=args.width, height=args.height)
    load_before = load_average()
    with tempfile.TemporaryDirectory() as root:
        store = ArtifactStore(root)
        seq_ids = [_add_log(root, seed, config) for seed in range(args.logs)]
        scratch, _ = _timed_run(root, seq_ids, "from-scratch")
        unchanged, _ = _timed_run(root, seq_ids, "nothing-new")
        seq_ids.append(_add_log(root, args.logs, config))
        grown, evaluated = _timed_run(root, seq_ids, "one-new-log")
        store.delete(CACHE_DIR)
        scratch_grown, _ = _timed_run(root, seq_ids, "from-scratch-grown")
        same = all(a.equals(b) for a, b in zip(_tables(root, "one-new-log"), _tables(root, "from-scratch-grown")))
    result = {"machine": machine_info(), "load_average_before": load_before, "load_average_after": load_average(),
              "world": {"frames": args.frames, "width": args.width, "height": args.height},
              "logs": args.logs, "seconds": {"from_scratch_n": scratch, "nothing_new_n": unchanged,
                                             "one_new_log_n_plus_1": grown,
                                             "from_scratch_n_plus_1": scratch_grown},
              "evaluated_in_one_new_log_run": evaluated, "tables_equal_fresh_evaluation": same}
    logger.info("n+1 logs: %.1f s from scratch, %.1f s with one new log (%.1fx); tables equal: %s", scratch_grown,
                grown, scratch_grown / grown, same)
    write_json_result(result, args.out / "grounding_cache.json")


if __name__ == "__main__":
    main()
