"""Tables built from figures the store already holds: reconstruction quality and stage throughput.

* ``reconstruction`` (:data:`RECONSTRUCTION_SPEC`): one row per stored scene, the trainer's test-frame image
  metrics (``scene.image_metrics``) and its size and wall time, as recorded in the scene's metrics;
* ``throughput`` (:data:`THROUGHPUT_SPEC`): one row per timed stage, the items it processed, their seconds and
  the items per hour, from the stages' recorded timings (a scene's ``wall_time_s``, an aligner's
  ``train_seconds``, the ``seconds_<stage>`` columns of mined edit attempts).

    table = reconstruction_table([SceneMetrics("seq0", "ab12...", {"psnr_test": 27.1, ...})])
    table = throughput_table([StageTiming("reconstruct", 1, 412.0), ...])

Nothing here is measured again: the rows are what the stages wrote.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import pyarrow as pa

from simsplat_core.eval.table_headlines import Headline
from simsplat_core.eval.table_spec import Column, TableSpec

#: The scene metrics of the ``reconstruction`` table: ``name -> (meaning, unit)``, in column order.
RECONSTRUCTION_METRICS: dict[str, tuple[str, str]] = {
    "psnr_test": ("PSNR of the test-frame renders", "dB"),
    "ssim_test": ("SSIM of the test-frame renders", ""),
    "psnr_test_dynamic": ("PSNR of the test frames inside the moving objects' boxes", "dB"),
    "ssim_test_dynamic": ("SSIM of the same", ""),
    "psnr_train": ("PSNR of the training frames", "dB"),
    "num_gaussians": ("Gaussians of the scene", "count"),
    "iterations": ("optimisation iterations", "count"),
    "wall_time_s": ("wall time of the reconstruction", "s"),
}

#: ``tables/reconstruction``: one row per stored scene (metrics a scene lacks are NaN).
RECONSTRUCTION_SPEC = TableSpec("reconstruction", "Reconstruction quality (test frames)", "(sequence, scene)", (
    Column("seq_id", pa.string(), "the reconstructed sequence"),
    Column("scene", pa.string(), "the scene's content hash (first 12 characters)"),
    *(Column(name, pa.float64(), meaning, unit) for name, (meaning, unit) in RECONSTRUCTION_METRICS.items()),
), keys=("seq_id", "scene"), headlines=(Headline("psnr_test", reduce="mean"), Headline("ssim_test", reduce="mean")))

#: ``tables/throughput``: one row per timed stage.
THROUGHPUT_SPEC = TableSpec("throughput", "Throughput per stage", "stage", (
    Column("stage", pa.string(), "the stage (reconstruct, align, mine:<loop stage>)"),
    Column("items", pa.int64(), "items the stage processed (scenes, aligner models, mining attempts)", "count"),
    Column("seconds", pa.float64(), "wall time summed over the items", "s"),
    Column("seconds_per_item", pa.float64(), "seconds / items", "s"),
    Column("items_per_hour", pa.float64(), "items / (seconds / 3600); NaN without time", "1/h"),
), keys=("stage",), digits=2, headlines=(Headline("items_per_hour"),))


@dataclass(frozen=True)
class SceneMetrics:
    """One stored scene's recorded metrics (``name -> value``; NaN where a value was not finite)."""

    seq_id: str
    scene_hash: str
    metrics: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class StageTiming:
    """Recorded wall time of one stage over ``items`` items."""

    stage: str
    items: int
    seconds: float


def reconstruction_table(scenes: Sequence[SceneMetrics]) -> pa.Table:
    """One :data:`RECONSTRUCTION_SPEC` row per scene, in the order given."""
    rows = [{"seq_id": s.seq_id, "scene": s.scene_hash[:12],
             **{name: float(s.metrics.get(name, math.nan)) for name in RECONSTRUCTION_METRICS}} for s in scenes]
    return RECONSTRUCTION_SPEC.table(rows)


def throughput_table(timings: Sequence[StageTiming]) -> pa.Table:
    """One :data:`THROUGHPUT_SPEC` row per stage (timings of the same stage summed), in first-seen order.

    Raises:
        ValueError: a negative item count or time (naming the stage).
    """
    totals: dict[str, list[float]] = {}
    for t in timings:
        if t.items < 0 or t.seconds < 0:
            raise ValueError(f"stage {t.stage!r}: negative items ({t.items}) or seconds ({t.seconds})")
        total = totals.setdefault(t.stage, [0, 0.0])
        total[0] += t.items
        total[1] += t.seconds
    rows = [{"stage": stage, "items": int(items), "seconds": seconds,
             "seconds_per_item": seconds / items if items else math.nan,
             "items_per_hour": items / (seconds / 3600.0) if seconds > 0 else math.nan}
            for stage, (items, seconds) in totals.items()]
    return THROUGHPUT_SPEC.table(rows)


__all__ = ["RECONSTRUCTION_METRICS", "RECONSTRUCTION_SPEC", "SceneMetrics", "StageTiming", "THROUGHPUT_SPEC",
           "reconstruction_table", "throughput_table"]
