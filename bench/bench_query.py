"""Benchmark: QueryEngine latency (cold and warm embedding cache) on a default-size synthetic scene.

    .venv/bin/python bench/bench_query.py [--seed 3] [--repeats 5]

The scene is built without reconstruction (``tests/.../language_scene_factory.py``): a default
``WorldConfig`` log (40 frames, 3 cameras of 240x160), the built-in captioner's captions on
ground-truth crops embedded with E5, label-built motion features, node-id maps from the instance
masks (``[40, 3, 160, 240]``). Scoring does not depend on where the features came from, so the
timings hold for reconstructed scenes with the same number of nodes.

Per query (singles, groups and no-match queries in several styles):

* ``cold_ms``: first ``ground`` on a fresh encoder cache and engine (E5 encodes the query's
  appearance / motion / location parts in one batch);
* ``warm_ms``: median of ``--repeats`` further calls (all parts cached: parsing and scoring only);
* ``masks_ms``: ``Grounding.masks(scene)`` (the per-frame pixel masks of the matches).

"Cold" is per query text part: a part shared with an earlier query ("pedestrian crossing" in "all
crossing pedestrians" and "the crossing pedestrian") is already cached. Also: the one-off codebook
build of a fresh engine (78 prototype phrases, E5 passages), and parsing alone. E5 latency depends on
the machine's load (it is recorded): on a shared 2-core machine an uncached text took 15 ms idle and
up to seconds under load. Writes ``bench/results/query.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from simsplat_core.eval.grounding.gt_scene import language_scene_from_log  # noqa: E402
from simsplat_core.language.codebooks import MotionCodebooks  # noqa: E402
from simsplat_core.language.grounding.engine import QueryEngine  # noqa: E402
from simsplat_core.language.grounding.parse import parse_query  # noqa: E402
from simsplat_core.language.text import E5TextEncoder  # noqa: E402
from simsplat_core.world import WorldConfig, generate_log  # noqa: E402

logger = logging.getLogger("bench.query")

QUERIES = (
    "the black car turning left at the intersection",
    "find me the pedestrian in a red shirt and blue pants crossing from left to right",
    "which SUV is parked on the right?",
    "all crossing pedestrians",
    "every parked car",
    "the purple bus",
    "the crossing pedestrian",
    "the white van stopped in front of us",
    "Could you please show me the silver sedan that is slowing down?",
    "the person in a gray jacket walking along the sidewalk",
    "Which cars are in the oncoming lane?",
    "the orange traffic cone by the curb",
    "that blue ride hanging a right by the crossroads",
    "the stop sign",
    "someone standing still on the pavement",
    "all the white SUVs",
    "the truck backing up",
    "the pedestrian crossing from right to left ahead of us",
    "the red hatchback changing lanes to the left",
    "the car behind us",
)


def _ms(seconds: float) -> float:
    return round(1000.0 * seconds, 3)


def run(seed: int, repeats: int) -> dict:
    t0 = time.perf_counter()
    log = generate_log(seed, WorldConfig())
    gen_s = time.perf_counter() - t0
    setup_encoder = E5TextEncoder()
    books = MotionCodebooks.build(setup_encoder)
    t0 = time.perf_counter()
    scene = language_scene_from_log(log, setup_encoder, "captioner", codebooks=books)
    build_s = time.perf_counter() - t0

    # one-off: codebooks of a fresh engine on a fresh encoder cache
    fresh = E5TextEncoder()
    t0 = time.perf_counter()
    MotionCodebooks.build(fresh)
    codebook_s = time.perf_counter() - t0

    encoder = E5TextEncoder()  # empty embedding cache: the first call per query is cold
    engine = QueryEngine(encoder, codebooks=books)
    rows = []
    for text in QUERIES:
        t0 = time.perf_counter()
        g = engine.ground(scene, text)
        cold = time.perf_counter() - t0
        warm = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            engine.ground(scene, text)
            warm.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        masks = g.masks(scene)
        mask_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(repeats):
            parse_query(text)
        parse_s = (time.perf_counter() - t0) / repeats
        rows.append(
            {
                "query": text,
                "cold_ms": _ms(cold),
                "warm_ms": _ms(statistics.median(warm)),
                "parse_ms": _ms(parse_s),
                "masks_ms": _ms(mask_s),
                "matches": [m.object_id for m in g.matches],
                "mask_pixels": int(masks.sum()),
                "message": g.message,
            }
        )
        logger.info("%-80s cold %7.1f ms  warm %6.2f ms  -> %s", text, rows[-1]["cold_ms"], rows[-1]["warm_ms"],
                    g.message)

    def summary(key: str) -> dict[str, float]:
        values = sorted(r[key] for r in rows)
        return {
            "median": round(statistics.median(values), 3),
            "p90": round(values[int(0.9 * (len(values) - 1))], 3),
            "max": round(values[-1], 3),
        }

    return {
        "machine": {
            "cpu": platform.machine(),
            "python": platform.python_version(),
            "cores": os.cpu_count(),
            "load_average_1m_at_end": round(os.getloadavg()[0], 2),
        },
        "scene": {
            "seed": seed,
            "nodes": len(scene.nodes),
            "captioned_nodes": sum(n.caption is not None for n in scene.nodes),
            "node_id_maps": list(scene.node_id_maps.shape),
            "world_generation_s": round(gen_s, 2),
            "language_scene_build_s": round(build_s, 2),
        },
        "codebook_build_fresh_encoder_ms": _ms(codebook_s),
        "encoder": encoder.name,
        "queries": len(rows),
        "cold_ms": summary("cold_ms"),
        "warm_ms": summary("warm_ms"),
        "parse_ms": summary("parse_ms"),
        "masks_ms": summary("masks_ms"),
        "per_query": rows,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "query.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    result = run(args.seed, args.repeats)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    logger.info("cold %s ms, warm %s ms -> %s", result["cold_ms"], result["warm_ms"], args.out)


if __name__ == "__main__":
    main()
