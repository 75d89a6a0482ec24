"""Evaluation runs for the dashboard tests' store: two runs with a declared ``editing`` table (the second with a
higher total rate, so its trend has two points) and, in the second, a ``search`` table (a mean headline)."""

from __future__ import annotations

from simsplat_core.eval.editing.outcomes import EDITING_SPEC
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from storage import ArtifactStore
from storage.runs import run_dir, run_table, write_run_tables

#: The evaluation runs, oldest first, and each one's total editing rate of ``ours``.
EVAL_RUNS: tuple[tuple[str, float], ...] = (("eval-20260101T000000000000Z", 0.75),
                                            ("eval-20260102T000000000000Z", 0.875))


def editing_rows(total_rate: float) -> list[dict[str, object]]:
    """``editing`` rows of two methods: one category and the total (``ours`` completes ``total_rate``)."""
    done = round(8 * total_rate)
    return [{"method": "ours", "category": "remove", "prompts": 8, "completed": done, "rate": done / 8},
            {"method": "ours", "category": "total", "prompts": 8, "completed": done, "rate": done / 8},
            {"method": "chatsim-like", "category": "remove", "prompts": 8, "completed": 4, "rate": 0.5},
            {"method": "chatsim-like", "category": "total", "prompts": 8, "completed": 4, "rate": 0.5}]


SEARCH_ROWS = [{"query": "a car turning left", "negative": False, "timestamp_ba": 0.9, "log_ba": 1.0, "hits": 2,
                "logs_true": 1, "logs_hit": 1, "seconds": 0.01},
               {"query": "a bus reversing", "negative": True, "timestamp_ba": None, "log_ba": None, "hits": 0,
                "logs_true": 0, "logs_hit": 0, "seconds": 0.01}]


def add_evaluation_runs(store: ArtifactStore) -> None:
    """Write :data:`EVAL_RUNS` into ``store`` (oldest first, so their ``written_at`` sort the same way)."""
    for k, (run_id, rate) in enumerate(EVAL_RUNS):
        tables = {EDITING_SPEC.name: run_table(EDITING_SPEC, EDITING_SPEC.table(editing_rows(rate)))}
        if k == len(EVAL_RUNS) - 1:
            tables[SEARCH_SPEC.name] = run_table(SEARCH_SPEC, SEARCH_SPEC.table(SEARCH_ROWS))
        write_run_tables(store, run_dir(run_id), tables, {"stage": "editing"})
