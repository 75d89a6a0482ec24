"""Task: evaluate language editing on the stored synthetic scenes (SIMSplat Table 3 and edit fidelity).

Thin: load each sequence's log (with its ground-truth images), the editor's context (stored scene graph,
language scene, asset bank: ``tasks.edit.load_edit_context``) and the world that generated the log; build
the prompt set from ground truth (inserts ask for the looks the bank holds); run every method on every
prompt and check it (``simsplat_core.eval.editing``); write the run's tables into ``OUT``:
``tables/editing.{parquet,md}``, ``tables/editing_infeasible``, ``tables/edit_fidelity``,
``tables/editing_outcomes`` (every method's result on every prompt, with the check's reason) and
``manifest.json``.
"""

from __future__ import annotations

import logging
import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import pyarrow as pa
import pyarrow.compute as pc
from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.eval.editing.evaluate import EvalConfig, EvalScene, editing_methods, evaluate_editing
from simsplat_core.eval.editing.outcomes import (
    completion_table,
    fidelity_table,
    infeasible_table,
    outcomes_table,
)
from simsplat_core.eval.editing.prompts import INFEASIBLE, PromptConfig, build_prompt_set, prompt_counts
from simsplat_core.eval.tables import markdown
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import default_text_encoder
from storage import ArtifactStore
from storage.assets import read_asset_bank
from storage.runs import RunTable, write_run_tables
from storage.schemas import editing_table_schema
from tasks.eval_scenes import asset_pools, load_truth_scene
from tasks.progress import StepProgress

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class EditingEvaluation:
    """What ``evaluate_editing_run`` returns (small).

    Attributes:
        seq_ids: the evaluated sequences.
        prompts: prompts per category (``prompt_counts``).
        completion: ``{method: {category: rate}}`` (categories and ``total``).
        refused: ``{method: share of the infeasible prompts refused}``.
        fidelity: ``{method: {category: {"psnr", "ssim", "psnr_region", "psnr_unedited", "edits"}}}``.
        edit_seconds: ``{method: {"mean", "median", "max"}}`` wall time of one edit (parse + ground + apply +
            validate).
        tables: ``name -> Parquet URI``.
        seconds: wall time of the whole evaluation.
    """

    seq_ids: tuple[str, ...]
    prompts: dict[str, int]
    completion: dict[str, dict[str, float]]
    refused: dict[str, float]
    fidelity: dict[str, dict[str, dict[str, float]]]
    edit_seconds: dict[str, dict[str, float]]
    tables: dict[str, str]
    seconds: float


def _rows(table: pa.Table) -> list[dict[str, Any]]:
    return table.to_pylist()


@task(name="evaluate-editing", retries=0, cache_policy=NO_CACHE)
def evaluate_editing_run(store_root: str, seq_ids: Sequence[str], out_root: str, out_relpath: str = "", *,
                         per_category: int = 30, infeasible: int = 20, methods: Sequence[str] | None = None,
                         render_all: bool = False, seed: int = 0) -> EditingEvaluation:
    """Evaluate editing on ``seq_ids`` of the store and write the run's tables (module docstring).

    Raises:
        FileNotFoundError: a log, language scene or the asset bank is missing (named).
        ValueError: no sequence given, or a sequence is not a synthetic log with ground-truth images.
        KeyError: an unknown method name.
    """
    if not seq_ids:
        raise ValueError("evaluate_editing_run: no sequences to evaluate")
    started = time.perf_counter()
    chosen = editing_methods(methods)
    store = ArtifactStore(store_root)
    engine = QueryEngine(default_text_encoder())
    bank = read_asset_bank(store)
    scenes = []
    for seq_id in seq_ids:
        scene = load_truth_scene(store, seq_id, engine=engine, bank=bank)
        scenes.append(EvalScene.prepare(scene.truth, scene.loaded.ctx))
    pools = asset_pools(bank)
    prompts = build_prompt_set([s.truth for s in scenes], PromptConfig(per_category, infeasible, seed), pools)
    progress = StepProgress("eval editing", headline="")
    outcomes = evaluate_editing(scenes, prompts, chosen, EvalConfig(render_all=render_all),
                                progress=lambda done, total, label: progress(done, total))
    unedited = {s.truth.seq_id: s.psnr_unedited for s in scenes}
    editing = completion_table(outcomes)
    refusals = infeasible_table(outcomes)
    fidelity = fidelity_table(outcomes, unedited)
    every = outcomes_table(outcomes)
    failed = every.filter(pc.invert(every["completed"]))
    tables = {
        "editing": RunTable(editing, editing_table_schema("editing"), markdown(editing)),
        "editing_infeasible": RunTable(refusals, editing_table_schema("editing_infeasible"), markdown(refusals)),
        "edit_fidelity": RunTable(fidelity, editing_table_schema("edit_fidelity"), markdown(fidelity, digits=2)),
        "editing_outcomes": RunTable(every, editing_table_schema("editing_outcomes"), markdown(
            failed, columns=("method", "category", "text", "refusal", "reason"))),
    }
    edit_seconds = {}
    for method in chosen:
        times = [o.seconds for o in outcomes if o.method == method.name and not o.refusal]
        edit_seconds[method.name] = ({"mean": statistics.fmean(times), "median": statistics.median(times),
                                      "max": max(times)} if times else {})
    by_op: dict[str, dict[str, float]] = {}
    for method in chosen:
        for op in ("insert", "remove", "modify", "replace"):
            scores = [o.fidelity.psnr for o in outcomes if o.method == method.name and o.completed
                      and o.fidelity is not None and o.prompt.intent.op == op and o.prompt.category != INFEASIBLE]
            if scores:
                by_op.setdefault(method.name, {})[op] = round(statistics.fmean(scores), 3)
    manifest = {"stage": "editing", "sequences": list(seq_ids), "prompts": prompt_counts(prompts),
                "fidelity_psnr_by_op": by_op,
                "methods": [m.name for m in chosen], "unedited_test_psnr": unedited,
                "asset_bank": bank.bank_hash, "edit_seconds": edit_seconds, "render_all": render_all,
                "seconds": round(time.perf_counter() - started, 3)}
    uris = write_run_tables(ArtifactStore(out_root), out_relpath, tables, manifest)
    completion = {m: {r["category"]: r["rate"] for r in _rows(editing) if r["method"] == m}
                  for m in (x.name for x in chosen)}
    refused = {r["method"]: r["rate"] for r in _rows(refusals)}
    fid = {m: {r["category"]: {k: r[k] for k in ("psnr", "ssim", "psnr_region", "psnr_unedited", "edits")}
               for r in _rows(fidelity) if r["method"] == m} for m in (x.name for x in chosen)}
    seconds = time.perf_counter() - started
    logger.info("editing on %d sequences, %d prompts (%d infeasible): %s (%.0f s)", len(seq_ids), len(prompts),
                sum(p.category == INFEASIBLE for p in prompts),
                ", ".join(f"{m} {c.get('total', float('nan')):.3f}" for m, c in completion.items()), seconds)
    return EditingEvaluation(tuple(seq_ids), prompt_counts(prompts), completion, refused, fid, edit_seconds, uris,
                             round(seconds, 3))


__all__ = ["EditingEvaluation", "evaluate_editing_run"]
