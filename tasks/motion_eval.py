"""Task: the multi-agent refinement evaluation (issue 11): ``tables/motion.{parquet,md}`` and ``manifest.json``.

Thin: load each real log (Waymo Open Motion scenario TFRecords, Argoverse 2 log directories), roll every
chosen predictor out on it (``simsplat_core.eval.refinement.real``), build the table
(``simsplat_core.eval.refinement.table``) and write it into ``OUT`` (``storage.runs.write_motion_table``).

The table is ``real_rows(...) + synthetic_rows(...)``: the synthetic (edit-based) rows on the store's scenes
are not written yet (:func:`synthetic_rows` returns none).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.eval.refinement.real import load_real_log, real_rows, replayed_summary, scenario_of_log
from simsplat_core.eval.refinement.table import motion_markdown, motion_rows, motion_table
from simsplat_core.motion.registry import make_predictor
from storage import ArtifactStore
from storage.runs import write_motion_table

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class MotionEvaluation:
    """What ``evaluate_motion_run`` returns (small).

    Attributes:
        real: the real logs evaluated (paths).
        rows: the table's rows.
        per_type: ``{dataset: {method: {agent type: {"ade_3s", "fde_3s", ...}}}}``.
        table: Parquet URI of ``tables/motion.parquet``.
        seconds: wall time.
    """

    real: tuple[str, ...]
    rows: list[dict[str, Any]]
    per_type: dict[str, Any]
    table: str
    seconds: float


def synthetic_rows(store_root: str | None, predictors: Sequence[str]) -> list[dict[str, Any]]:
    """The edit-based rows on the store's synthetic scenes: not implemented yet (none)."""
    del store_root, predictors
    return []


@task(name="evaluate-motion", retries=0, cache_policy=NO_CACHE)
def evaluate_motion_run(out_root: str, real: Sequence[str | Path], predictors: Sequence[str],
                        store_root: str | None = None, out_relpath: str = "") -> MotionEvaluation:
    """Evaluate ``predictors`` on the ``real`` logs and write the motion table (module docstring).

    Raises:
        KeyError: an unknown or unavailable predictor.
        FileNotFoundError: a real log path that does not exist.
        CorruptLogError: a damaged log (the loader's error names the file).
        ValueError: no real log given, or a log too short to predict on.
    """
    started = time.perf_counter()
    chosen = [make_predictor(name) for name in predictors]
    if not real:
        raise ValueError("evaluate_motion_run: no real logs to evaluate (pass --real)")
    scenarios = [scenario_of_log(load_real_log(path)) for path in real]
    evaluation = real_rows(scenarios, chosen)
    rows = motion_rows(evaluation.rows, synthetic_rows(store_root, predictors))
    table = motion_table(rows)
    manifest = {"stage": "motion", "real": [str(p) for p in real], "predictors": list(predictors),
                "scenarios": [{"dataset": s.dataset, "seq_id": s.seq_id, "steps": s.states.num_steps,
                               "agents": s.states.num_agents, "start_step": s.start_step, "resampled": s.resampled,
                               "lanes": len(s.map.lanes), "road_edges": len(s.map.road_edges)} for s in scenarios],
                "per_type": evaluation.per_type, "replayed": replayed_summary(evaluation.scores),
                "synthetic": "not evaluated yet", "seconds": round(time.perf_counter() - started, 3)}
    uri = write_motion_table(ArtifactStore(out_root), out_relpath, table, motion_markdown(table), manifest)
    seconds = round(time.perf_counter() - started, 3)
    logger.info("motion on %d real logs, predictors %s: %s (%.1f s)", len(scenarios), list(predictors), uri, seconds)
    return MotionEvaluation(tuple(str(p) for p in real), rows, evaluation.per_type, uri, seconds)


__all__ = ["MotionEvaluation", "evaluate_motion_run", "synthetic_rows"]
