"""Benchmark: synthetic world generation time and bytes on disk per sequence.

    .venv/bin/python bench/bench_world.py [--seeds 3] [--frames 40] [--width 240 --height 160]

Prints a table and writes ``bench/results/world.json``. Generation and writing are timed separately;
numba compilation is excluded by a warm-up sequence (its time is reported too).
"""

from __future__ import annotations

import argparse
import json
import logging
import platform
import resource
import statistics
import tempfile
import time
from pathlib import Path

from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, write_scene_log

logger = logging.getLogger("bench.world")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--width", type=int, default=240)
    parser.add_argument("--height", type=int, default=160)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "world.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    config = WorldConfig(num_frames=args.frames, width=args.width, height=args.height)

    started = time.perf_counter()
    generate_log(seed=10_000, config=WorldConfig(num_frames=2, width=32, height=24))
    warmup_s = time.perf_counter() - started

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        store = ArtifactStore(tmp)
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            log = generate_log(seed=seed, config=config)
            t1 = time.perf_counter()
            written = write_scene_log(store, log)
            t2 = time.perf_counter()
            rows.append({"seed": seed, "generate_s": t1 - t0, "write_s": t2 - t1, "bytes": written.bytes,
                         "objects": len(log.objects), "images": len(log.images)})
            logger.info("seed %d: generate %.2f s, write %.2f s, %.2f MB, %d objects", seed, t1 - t0, t2 - t1,
                        written.bytes / 1e6, len(log.objects))
    result = {
        "config": {"frames": args.frames, "width": args.width, "height": args.height, "cameras": len(config.cameras)},
        "machine": {"cpu": platform.processor() or platform.machine(), "python": platform.python_version()},
        "warmup_compile_s": round(warmup_s, 2),
        "median_generate_s": round(statistics.median(r["generate_s"] for r in rows), 3),
        "median_write_s": round(statistics.median(r["write_s"] for r in rows), 3),
        "median_bytes": int(statistics.median(r["bytes"] for r in rows)),
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "runs": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    logger.info("median: generate %.2f s, write %.2f s, %.2f MB per sequence (warm-up %.1f s); peak RSS %.0f MB",
                result["median_generate_s"], result["median_write_s"], result["median_bytes"] / 1e6, warmup_s,
                result["peak_rss_mb"])


if __name__ == "__main__":
    main()
