"""Task: evaluate free-form grounding on the stored language scenes of synthetic logs (SIMSplat Tables 2, 3).

Builds the benchmark from the logs' ground truth (paraphrased queries per target, group and no-match
queries, instance masks), runs every method of ``grounding_methods`` on the stored language scenes
(whose node-id maps were rendered from the reconstructed Gaussians) and writes the tables into the
run directory: ``tables/grounding.{parquet,md}`` (Table 2), ``tables/grounding_ablation.{parquet,md}``
(Table 3) and ``tables/grounding_outcomes.parquet`` (every method's answer to every query).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.eval.grounding.benchmark import BenchmarkConfig, build_benchmark, query_counts
from simsplat_core.eval.grounding.methods import ABLATION_ROW_METHODS, COMPARISON_ROWS, grounding_methods
from simsplat_core.eval.grounding.metrics import evaluate_grounding, latency_of, summarise_answers
from simsplat_core.eval.grounding.tables import (
    ABLATION_SPEC,
    GROUNDING_SPEC,
    OUTCOMES_SPEC,
    ablation_table,
    grounding_outcomes_table,
    grounding_table,
)
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import default_text_encoder
from storage import ArtifactStore, read_scene_log, require_log_manifest
from storage.alignment import ALIGNMENT_DIR
from storage.grounding_outcomes import read_cached_outcomes, write_cached_outcomes
from storage.keys import config_settings, content_key
from storage.language_scenes import list_language_scenes, read_language_scene
from storage.runs import run_table, write_run_tables
from tasks.code_version import source_digest
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class GroundingEvaluation:
    """What ``evaluate_grounding_run`` returns (small).

    Attributes:
        seq_ids: the evaluated sequences.
        queries: benchmark queries (all methods answer each).
        scores: ``{method: {category: {"acc", "viou", "queries"}}}``.
        tables: ``name -> Parquet URI``.
        seconds: wall time.
    """

    seq_ids: tuple[str, ...]
    queries: int
    scores: dict[str, dict[str, dict[str, float]]]
    tables: dict[str, str]
    seconds: float


#: The code whose changes change a sequence's grounding answers (part of each cached entry's key).
GROUNDING_CODE = ("simsplat_core.eval.grounding", "simsplat_core.language", "tasks.grounding_eval")


def outcomes_key(store: ArtifactStore, seq_id: str, config: BenchmarkConfig, code: str) -> str:
    """The key of ``seq_id``'s grounding outcomes: its log, its newest language scene, the benchmark settings and
    the code.

    Raises:
        FileNotFoundError: the log or its language scene is missing (named).
    """
    log_key = require_log_manifest(store, seq_id, "the grounding benchmark")["key"]
    scenes = list_language_scenes(store, seq_id)
    if not scenes:
        raise FileNotFoundError(f"{store.uri(ALIGNMENT_DIR)}: no language scene of {seq_id!r} "
                                f"(run the alignment stage: simsplat align / simsplat run)")
    model_hash, language_hash = scenes[0]
    return content_key("grounding_outcomes", seq_id, log_key, model_hash, language_hash, config_settings(config), code)


def _evaluate_sequences(store: ArtifactStore, seq_ids: list[str], config: BenchmarkConfig
                        ) -> dict[str, pa.Table | None]:
    """Every method's answers on each of ``seq_ids`` as outcome rows (``None``: the log has no ground truth)."""
    logs = {seq_id: read_scene_log(store, seq_id) for seq_id in seq_ids}
    out: dict[str, pa.Table | None] = {s: None for s, log in logs.items()
                                       if not any(img.instance is not None for img in log.images)}
    logs = {s: log for s, log in logs.items() if s not in out}
    if not logs:
        return out
    scenes = [read_language_scene(store, seq_id, with_records=False).scene for seq_id in logs]
    bench = build_benchmark(list(logs.values()), config)
    encoder = default_text_encoder()
    engine = QueryEngine(encoder)
    embedded = engine.prepare([q.text for q in bench.queries])  # batched: ~4x faster than one by one
    logger.info("embedded %d query texts and parts for %d queries", embedded, len(bench.queries))
    outcomes = grounding_outcomes_table(evaluate_grounding(scenes, bench, grounding_methods(encoder, logs,
                                                                                           engine=engine)))
    seq_column = np.asarray(outcomes.column("seq_id").to_pylist(), dtype=object)
    for seq_id in logs:
        out[seq_id] = outcomes.take(np.flatnonzero(seq_column == seq_id))
    return out


@task(name="evaluate-grounding", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def evaluate_grounding_run(store_root: str, seq_ids: list[str], out_root: str, out_relpath: str = "",
                           benchmark: BenchmarkConfig | None = None) -> GroundingEvaluation:
    """Evaluate grounding on the newest language scene of each of ``seq_ids`` and write the run's tables.

    A sequence's answers depend on nothing else, so they are kept per sequence (``storage.grounding_outcomes``) and
    a run evaluates only the sequences whose log, language scene, settings or code it has not seen; the tables are
    the same as evaluating every sequence afresh (the answers' timings are those of the run that computed them).

    Args:
        store_root: the store holding ``logs/`` (with ground-truth instance masks) and ``alignment/``.
        out_root, out_relpath: the run directory (``ArtifactStore(out_root)`` / ``out_relpath``).

    Raises:
        FileNotFoundError: a log or language scene is missing (named).
        ValueError: no sequence given, or none has ground-truth instance masks.
    """
    if not seq_ids:
        raise ValueError("evaluate_grounding_run: no sequences to evaluate")
    started = time.perf_counter()
    store = ArtifactStore(store_root)
    config = benchmark or BenchmarkConfig()
    code = source_digest(*GROUNDING_CODE)
    schema = OUTCOMES_SPEC.schema
    keys = {seq_id: outcomes_key(store, seq_id, config, code) for seq_id in seq_ids}
    entries = {seq_id: read_cached_outcomes(store, seq_id, keys[seq_id], schema) for seq_id in seq_ids}
    missing = [seq_id for seq_id, entry in entries.items() if entry is None]
    logger.info("grounding benchmark: %d of %d sequence(s) to evaluate, %d answered before", len(missing),
                len(seq_ids), len(seq_ids) - len(missing))
    per_sequence: dict[str, pa.Table | None] = {s: e.rows for s, e in entries.items() if e is not None}
    for seq_id, rows in _evaluate_sequences(store, missing, config).items():
        write_cached_outcomes(store, seq_id, keys[seq_id], rows, schema)
        per_sequence[seq_id] = rows
    without_truth = [s for s in seq_ids if per_sequence[s] is None]
    evaluated = [s for s in seq_ids if per_sequence[s] is not None]
    if not evaluated:
        raise ValueError(f"no ground-truth instance masks in {sorted(seq_ids)}: grounding needs synthetic logs")
    outcomes = pa.concat_tables([per_sequence[s] for s in evaluated])
    methods = outcomes.column("method").to_pylist()
    summary = summarise_answers(zip(methods, outcomes.column("category").to_pylist(),
                                    outcomes.column("correct").to_pylist(), outcomes.column("viou").to_pylist()))
    latency = latency_of([t for m, t in zip(methods, outcomes.column("seconds").to_pylist()) if m == "ours"])
    queries = sum(m == methods[0] for m in methods)  # every method answers every query once
    table2 = grounding_table(summary, COMPARISON_ROWS)
    table3 = ablation_table(summary, ABLATION_ROW_METHODS)
    tables = {
        spec.name: run_table(spec, table)
        for spec, table in ((GROUNDING_SPEC, table2), (ABLATION_SPEC, table3), (OUTCOMES_SPEC, outcomes))
    }
    first_method = [(k, c) for m, k, c in zip(methods, outcomes.column("kind").to_pylist(),
                                              outcomes.column("category").to_pylist()) if m == methods[0]]
    manifest = {"stage": "grounding", "sequences": sorted(evaluated), "skipped_without_ground_truth": without_truth,
                "queries": queries, "query_counts": query_counts(first_method), "latency_ours_s": latency,
                "sequences_evaluated_this_run": sorted(missing)}
    uris = write_run_tables(ArtifactStore(out_root), out_relpath, tables, manifest)
    scores = {m: {c: {"acc": s.accuracy, "viou": s.viou, "queries": float(s.queries)} for c, s in per.items()}
              for m, per in summary.items()}
    seconds = time.perf_counter() - started
    ours = summary["ours"]["total"]
    logger.info("grounding on %d sequences, %d queries: ours acc %.3f vIoU %.3f (%.1f s)", len(evaluated), queries,
                ours.accuracy, ours.viou, seconds)
    return GroundingEvaluation(tuple(sorted(evaluated)), queries, scores, uris, round(seconds, 3))
