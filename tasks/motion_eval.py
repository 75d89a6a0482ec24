"""Task: the multi-agent refinement evaluation: ``tables/motion.{parquet,md}``,
``tables/motion_outcomes.{parquet,md}`` and ``manifest.json``.

Thin: load inputs, call ``simsplat_core.eval.refinement``, write the tables into ``OUT``
(``storage.runs.write_run_tables``). Rows, in this order:

* the synthetic (edit-based) rows on the store's aligned scenes (:func:`synthetic_rows`): the editing
  benchmark's insert / modify prompts and the interaction prompts, applied by the editor in every refinement
  mode (``eval.refinement.synthetic``), plus the scenes' log row;
* the real-data rows: every chosen predictor rolled out on every 9.1 s window of each real log
  (``eval.refinement.windows``, ``window_stride`` steps apart; ``eval.refinement.real``: method ``full``, the ego
  on its log), next to the log's own row;
* the scripted edits of the real logs (``eval.refinement.real_edits``, dataset ``"<dataset>+edits"``) in every
  mode with the edit predictor, the ego reacting too.

``motion_outcomes`` has one row per (edit case, mode) of the synthetic and real edits, with the failing agents and
what happened to each; its Markdown lists the failed and refused ones. With ``diagnose``, ``motion_stalls`` too
(``eval.refinement.diagnosis``): one row per agent stopped in a real rollout but moving in the log, with what
stopped it.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.eval.editing.prompts import PromptConfig, build_prompt_set
from simsplat_core.eval.refinement.diagnosis import STALLS_SPEC, Stall, stalls_table
from simsplat_core.eval.refinement.interactions import build_interactions
from simsplat_core.eval.refinement.real import load_real_log, real_rows, replayed_summary, scenario_of_log
from simsplat_core.eval.refinement.real_edits import edits_dataset, evaluate_real_edits
from simsplat_core.eval.refinement.synthetic import (
    BENCH_MODES,
    EDITING_CATEGORIES,
    MotionOutcome,
    evaluate_motion,
    log_outcomes,
    motion_cases,
    outcome_row,
)
from simsplat_core.eval.refinement.synthetic import synthetic_rows as rows_of_outcomes
from simsplat_core.eval.refinement.table import (
    MOTION_SPEC,
    OUTCOMES_SPEC,
    motion_rows,
    motion_table,
    outcomes_table,
)
from simsplat_core.eval.refinement.windows import DEFAULT_STRIDE, windows_of
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import default_text_encoder
from simsplat_core.motion.registry import DEFAULT_PREDICTOR, make_predictor
from storage import ArtifactStore
from storage.assets import read_asset_bank
from storage.runs import run_table, write_run_tables
from tasks.eval_scenes import asset_pools, load_truth_scene
from tasks.progress import StepProgress

logger = logging.getLogger(__name__)

Progress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class SyntheticMotion:
    """What :func:`synthetic_rows` returns.

    Attributes:
        rows: the ``synthetic`` rows (log, then one per mode).
        outcomes: every (case, mode) outcome.
        cases: cases per kind (editing categories and interaction kinds).
        seq_ids: the scenes.
    """

    rows: list[dict[str, Any]]
    outcomes: list[MotionOutcome]
    cases: dict[str, int] = field(default_factory=dict)
    seq_ids: tuple[str, ...] = ()


@dataclass(frozen=True)
class MotionEvaluation:
    """What ``evaluate_motion_run`` returns (small).

    Attributes:
        real: the real logs evaluated (paths).
        rows: the table's rows.
        per_type: ``{dataset: {predictor: {agent type: {"ade_3s", "fde_3s", ...}}}}``.
        table: Parquet URI of ``tables/motion.parquet`` (``motion_outcomes.parquet`` beside it).
        seconds: wall time.
        sequences: the store's scenes evaluated.
        real_edits: ``{seq_id: {edit: "" when applied, else why not}}``.
        stalls: the stalled agents of the real rollouts (``diagnose`` only).
        stalls_table: Parquet URI of ``tables/motion_stalls.parquet`` (``""``: not diagnosed).
    """

    real: tuple[str, ...]
    rows: list[dict[str, Any]]
    per_type: dict[str, Any]
    table: str
    seconds: float
    sequences: tuple[str, ...] = ()
    real_edits: dict[str, dict[str, str]] = field(default_factory=dict)
    stalls: list[Stall] = field(default_factory=list)
    stalls_table: str = ""


@dataclass(frozen=True)
class RealOptions:
    """How the real logs are evaluated.

    Attributes:
        window_stride: steps between the starts of each log's 9.1 s windows (``eval.refinement.windows``).
        diagnose: also write ``motion_stalls`` (``eval.refinement.diagnosis``).
        edits: also evaluate the scripted edits of the real logs (``eval.refinement.real_edits``).
    """

    window_stride: int = DEFAULT_STRIDE
    diagnose: bool = False
    edits: bool = True


def synthetic_rows(store_root: str, seq_ids: Sequence[str], predictor: str = DEFAULT_PREDICTOR, *,
                   per_category: int = 30, per_kind: int = 3, seed: int = 0, modes: Sequence[str] = tuple(BENCH_MODES),
                   progress: Progress | None = None) -> SyntheticMotion:
    """The edit-based rows on the store's scenes ``seq_ids`` (module docstring): the editing benchmark's prompts of
    ``synthetic.EDITING_CATEGORIES`` (``per_category`` each over all scenes, no infeasible ones) and
    ``per_kind`` interaction prompts of each kind per scene, each applied in every mode with ``predictor``.

    Raises:
        FileNotFoundError: a log, language scene or the asset bank is missing (named).
        KeyError: an unknown predictor.
    """
    chosen = make_predictor(predictor)
    store = ArtifactStore(store_root)
    bank = read_asset_bank(store)
    engine = QueryEngine(default_text_encoder())
    scenes = [load_truth_scene(store, s, engine=engine, bank=bank, predictor=chosen) for s in seq_ids]
    truths = [s.truth for s in scenes]
    prompts = [p for p in build_prompt_set(truths, PromptConfig(per_category, 0, seed), asset_pools(bank))
               if p.category in EDITING_CATEGORIES]
    cases = motion_cases(prompts, build_interactions(truths, per_kind=per_kind, seed=seed))
    contexts = {s.truth.seq_id: s.loaded.ctx for s in scenes}
    outcomes = evaluate_motion(contexts, cases, modes, progress=progress)
    counts = dict(Counter(c.kind for c in cases))
    rows = rows_of_outcomes(outcomes, log_outcomes(contexts), predictor=chosen.name)
    return SyntheticMotion(rows, outcomes, counts, tuple(seq_ids))


@task(name="evaluate-motion", retries=0, cache_policy=NO_CACHE)
def evaluate_motion_run(out_root: str, real: Sequence[str | Path], predictors: Sequence[str],
                        store_root: str | None = None, out_relpath: str = "", *, seq_ids: Sequence[str] = (),
                        edit_predictor: str = DEFAULT_PREDICTOR,
                        per_category: int = 30, per_kind: int = 3,
                        options: RealOptions = RealOptions()) -> MotionEvaluation:
    """Evaluate refinement and write the motion tables (module docstring); ``seq_ids`` are the store's scenes (none:
    no synthetic rows); ``options``: the real logs' windows and diagnosis.

    Raises:
        KeyError: an unknown or unavailable predictor.
        FileNotFoundError: a real log path or a store artifact that does not exist.
        CorruptLogError: a damaged log (the loader's error names the file).
        ValueError: neither real logs nor scenes given, or a log too short to predict on.
    """
    started = time.perf_counter()
    chosen = [make_predictor(name) for name in predictors]
    editor_predictor = make_predictor(edit_predictor)
    if not real and not (store_root and seq_ids):
        raise ValueError("evaluate_motion_run: nothing to evaluate (pass --real logs or a --store with scenes)")
    scenarios = [scenario_of_log(load_real_log(path)) for path in real]
    synthetic = SyntheticMotion([], [])
    if store_root and seq_ids:
        bar = StepProgress("eval motion (synthetic edits)", headline="")
        synthetic = synthetic_rows(store_root, seq_ids, edit_predictor, per_category=per_category, per_kind=per_kind,
                                   progress=lambda done, total, label: bar(done, total))
    real_bar = StepProgress("eval motion (real logs)", headline="")
    windows = [w for s in scenarios for w in windows_of(s, options.window_stride)]
    evaluation = real_rows(windows, chosen, progress=lambda done, total, label: real_bar(done, total),
                           diagnose=options.diagnose)
    edited = evaluate_real_edits(scenarios, editor_predictor) if options.edits and scenarios else None
    rows = motion_rows(synthetic.rows, evaluation.rows, edited.rows if edited is not None else [])
    table = motion_table(rows)
    outcome_rows = [outcome_row(o) for o in synthetic.outcomes]
    if edited is not None:
        outcome_rows += [outcome_row(o, edits_dataset(edited.datasets[o.case.seq_id])) for o in edited.outcomes]
    outcomes = outcomes_table(outcome_rows)
    manifest = {"stage": "motion", "real": [str(p) for p in real], "predictors": list(predictors),
                "edit_predictor": editor_predictor.name, "sequences": list(synthetic.seq_ids),
                "synthetic_cases": synthetic.cases,
                "scenarios": [{"dataset": s.dataset, "seq_id": s.seq_id, "steps": s.states.num_steps,
                               "agents": s.states.num_agents, "start_step": s.start_step, "resampled": s.resampled,
                               "lanes": len(s.map.lanes), "road_edges": len(s.map.road_edges),
                               "windows": sum(w.seq_id.split("@")[0] == s.seq_id for w in windows)}
                              for s in scenarios],
                "window_stride": options.window_stride,
                "real_edits": edited.applied if edited is not None else {},
                "per_type": evaluation.per_type, "replayed": replayed_summary(evaluation.scores),
                "seconds": round(time.perf_counter() - started, 3)}
    specs = [(MOTION_SPEC, table), (OUTCOMES_SPEC, outcomes)]
    if options.diagnose:
        specs.append((STALLS_SPEC, stalls_table(evaluation.stalls)))
    tables = {spec.name: run_table(spec, t) for spec, t in specs}
    written = write_run_tables(ArtifactStore(out_root), out_relpath, tables, manifest)
    uri = written[MOTION_SPEC.name]
    seconds = round(time.perf_counter() - started, 3)
    logger.info("motion on %d scenes, %d real logs, predictors %s: %s (%.1f s)", len(synthetic.seq_ids),
                len(scenarios), list(predictors), uri, seconds)
    return MotionEvaluation(tuple(str(p) for p in real), rows, evaluation.per_type, uri, seconds,
                            synthetic.seq_ids, edited.applied if edited is not None else {}, evaluation.stalls,
                            written.get(STALLS_SPEC.name, ""))


__all__ = ["MotionEvaluation", "RealOptions", "SyntheticMotion", "evaluate_motion_run", "synthetic_rows"]
