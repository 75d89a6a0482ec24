"""Benchmark: where time and memory go in a run's store-wide steps as the store grows.

    .venv/bin/python bench/bench_store_growth.py --store /work/scale-store [--sizes 10 25 50] [--repeats 3]
        [--scratch DIR] [--train-aligner] [--out bench/results] [--name store_growth]

From one built store (e.g. ``simsplat run --store S --sequences 50 --mine 1 --iterations 30 --frames 20 --width 120
--height 80``) it makes a sub-store per size holding the first N logs (hard links: no copy), with their scenes,
their language scenes under every stored aligner and the asset banks, and times the steps of a scheduled run that
read the whole store rather than one sequence:

* ``list_logs``, ``resolve_seq_ids``: listing the store's logs;
* ``stored_logs_and_plans``: the ``StoredLog`` and stage plan of every log (``flows.pipeline.store_logs``' work);
* ``sequences_with_scene``, ``sequences_with_language_scene``: ``storage.inventory`` checks;
* ``aligner_key``: the aligner's content key over every log's manifest and the stored-model check
  (``train_motion_aligner``'s path when the model is stored), ``load_aligner``: loading the newest stored model;
* ``asset_sources``: the asset bank's inputs (newest scene and its language scene per log: the bank's key);
* ``search_preparation``: every log read and its per-frame facts computed (``tasks.search.load_store``);
* ``aligner_training`` (with ``--train-aligner``): reading every log and fitting the motion aligner on them
  (what a run does whenever the store's set of logs changed and no stored aligner covers it).

Per step and size: the median wall time of ``--repeats`` calls, the time per log, and the peak of Python allocations
(``tracemalloc``, a separate call; ``aligner_training`` and ``search_preparation`` are timed once, allocations
included). A step that grows faster than linearly shows as a rising time per log. The 1-minute load average is
recorded with every size: the machine is shared, so compare sizes of one run. Writes ``<out>/<name>.json``.
"""

from __future__ import annotations

import argparse
import logging
import os
import shutil
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from run_info import load_average, machine_info, write_json_result  # noqa: E402

from storage import ArtifactStore, list_logs, require_log_manifest  # noqa: E402
from storage.alignment import list_aligner_models, read_aligner_manifest  # noqa: E402
from storage.inventory import LANGUAGE_SCENE, SCENE, sequences_with  # noqa: E402
from tasks.align import aligner_hash, load_motion_aligner  # noqa: E402
from tasks.assets import asset_sources  # noqa: E402
from tasks.logs import stored_log  # noqa: E402
from tasks.search import load_store  # noqa: E402
from tasks.stages import decide_stages, resolve_seq_ids  # noqa: E402

logger = logging.getLogger("bench.store_growth")


def _link_tree(src: Path, dst: Path) -> None:
    shutil.copytree(src, dst, copy_function=os.link, dirs_exist_ok=True)


def make_substore(full: Path, seq_ids: list[str], dst: Path) -> Path:
    """A store at ``dst`` holding ``seq_ids``' logs, scenes and language scenes (every aligner) and the asset banks
    of ``full``, hard-linked."""
    shutil.rmtree(dst, ignore_errors=True)
    for seq_id in seq_ids:
        for kind in ("logs", "scenes"):
            if (full / kind / seq_id).is_dir():
                _link_tree(full / kind / seq_id, dst / kind / seq_id)
    for model in sorted((full / "alignment").iterdir()) if (full / "alignment").is_dir() else []:
        for entry in model.iterdir():
            if entry.name != "scenes":
                (_link_tree(entry, dst / "alignment" / model.name / entry.name) if entry.is_dir()
                 else (dst / "alignment" / model.name).mkdir(parents=True, exist_ok=True)
                 or os.link(entry, dst / "alignment" / model.name / entry.name))
        for seq_id in seq_ids:
            if (model / "scenes" / seq_id).is_dir():
                _link_tree(model / "scenes" / seq_id, dst / "alignment" / model.name / "scenes" / seq_id)
    if (full / "assets").is_dir():
        _link_tree(full / "assets", dst / "assets")
    return dst


def _stored_logs_and_plans(root: str) -> int:
    logs = [stored_log(root, seq_id) for seq_id in resolve_seq_ids(root)]
    return len([decide_stages(s.summary.seq_id, s.summary.source, s.summary.num_images) for s in logs])


def _aligner_key(root: str) -> bool:
    from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
    from simsplat_core.language.text import default_text_encoder

    store = ArtifactStore(root)
    keys = [require_log_manifest(store, seq_id)["key"] for seq_id in resolve_seq_ids(root)]
    key = aligner_hash(keys, MotionAlignerConfig(), default_text_encoder().name)
    return read_aligner_manifest(store, key) is not None


def _load_newest_aligner(root: str) -> object:
    store = ArtifactStore(root)
    return load_motion_aligner(store, list_aligner_models(store)[0])


def _aligner_training(root: str) -> int:
    from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
    from simsplat_core.language.text import default_text_encoder
    from storage import read_scene_log

    store = ArtifactStore(root)
    logs = [read_scene_log(store, seq_id, load_images=False) for seq_id in resolve_seq_ids(root)]
    return len(MotionAligner.fit(logs, MotionAlignerConfig(), default_text_encoder()).history)


def steps(train_aligner: bool) -> dict[str, Callable[[str], Any]]:
    """The measured steps by name, each a call on a store root."""
    named: dict[str, Callable[[str], Any]] = {
        "list_logs": lambda root: len(list_logs(ArtifactStore(root))),
        "resolve_seq_ids": lambda root: len(resolve_seq_ids(root)),
        "stored_logs_and_plans": _stored_logs_and_plans,
        "sequences_with_scene": lambda root: len(sequences_with(ArtifactStore(root), SCENE)),
        "sequences_with_language_scene": lambda root: len(sequences_with(ArtifactStore(root), LANGUAGE_SCENE)),
        "aligner_key": _aligner_key,
        "load_aligner": _load_newest_aligner,
        "asset_sources": lambda root: len(asset_sources(ArtifactStore(root))),
        "search_preparation": lambda root: len(load_store(root)),
    }
    if train_aligner:
        named["aligner_training"] = _aligner_training
    return named


#: Steps too slow to repeat: timed once, with the allocation peak of that same call.
ONCE = ("aligner_training", "search_preparation")


def measure_once(step: Callable[[str], Any], root: str) -> dict[str, float]:
    """Wall time and peak of Python allocations of one call."""
    tracemalloc.start()
    started = time.perf_counter()
    step(root)
    wall = time.perf_counter() - started
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return {"median_s": round(wall, 4), "min_s": round(wall, 4), "peak_alloc_mb": round(peak / 2**20, 2),
            "calls": 1}


def measure(step: Callable[[str], Any], root: str, repeats: int) -> dict[str, float]:
    """Median wall time of ``repeats`` calls (after one warm-up) and the peak of Python allocations of one call."""
    step(root)
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        step(root)
        times.append(time.perf_counter() - started)
    tracemalloc.start()
    step(root)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return {"median_s": round(statistics.median(times), 4), "min_s": round(min(times), 4),
            "peak_alloc_mb": round(peak / 2**20, 2)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--store", required=True, type=Path, help="a built local store (the largest size)")
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 25, 50])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scratch", type=Path, default=None, help="where the sub-stores go (default: beside STORE)")
    parser.add_argument("--train-aligner", action="store_true", help="also time the aligner's training per size")
    parser.add_argument("--skip", nargs="*", default=[], help="steps not to measure (e.g. search_preparation)")
    parser.add_argument("--out", default="bench/results")
    parser.add_argument("--name", default="store_growth")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s", force=True)
    logging.getLogger("tasks").setLevel(logging.WARNING)
    full = args.store.resolve()
    seq_ids = list_logs(ArtifactStore(str(full)))
    scratch = args.scratch or full.parent / f"{full.name}-subsets"
    models = len(list((full / "alignment").iterdir())) if (full / "alignment").is_dir() else 0
    result: dict[str, Any] = {"machine": machine_info(),
                              "store": str(full), "logs_in_store": len(seq_ids), "aligners_in_store": models,
                              "repeats": args.repeats, "sizes": {}}
    named = {name: step for name, step in steps(args.train_aligner).items() if name not in args.skip}
    if not list_aligner_models(ArtifactStore(str(full))):
        logger.warning("no aligner in %s yet: load_aligner not measured", full)
        named.pop("load_aligner", None)
    for size in sorted(set(args.sizes)):
        if size > len(seq_ids):
            logger.warning("size %d skipped: the store holds %d logs", size, len(seq_ids))
            continue
        root = str(make_substore(full, seq_ids[:size], scratch / f"n{size}"))
        row: dict[str, Any] = {"load_before": load_average(), "steps": {}}
        for name, step in named.items():
            figures = measure_once(step, root) if name in ONCE else measure(step, root, args.repeats)
            figures["ms_per_log"] = round(1e3 * figures["median_s"] / size, 3)
            row["steps"][name] = figures
            logger.info("n=%3d %-30s %8.3f s  %7.2f ms/log  peak %7.1f MB", size, name, figures["median_s"],
                        figures["ms_per_log"], figures["peak_alloc_mb"])
        row["load_after"] = load_average()
        result["sizes"][str(size)] = row
        write_result(result, list(named), Path(args.out) / f"{args.name}.json")  # after every size: slow steps
    return 0


def write_result(result: dict[str, Any], names: list[str], path: Path) -> None:
    """Write ``result`` with the growth of each step from the smallest to the largest size measured so far."""
    sizes = sorted(result["sizes"], key=int)
    if len(sizes) > 1:
        small, large = (result["sizes"][s]["steps"] for s in (sizes[0], sizes[-1]))
        result["growth"] = {name: {"size_ratio": round(int(sizes[-1]) / int(sizes[0]), 2),
                                   "time_ratio": round(large[name]["median_s"] / max(small[name]["median_s"], 1e-9),
                                                       2)}
                            for name in names if name in small and name in large}
    write_json_result(result, path)


if __name__ == "__main__":
    raise SystemExit(main())
