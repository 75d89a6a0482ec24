"""The grounding benchmark keeps each sequence's answers: a run evaluates only what it has not seen, and its tables
equal those of evaluating every sequence afresh."""

from __future__ import annotations

import logging
from pathlib import Path

import pyarrow as pa
import pytest

from simsplat_core.eval.grounding.tables import GROUNDING_SPEC, OUTCOMES_SPEC
from simsplat_core.world import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import ArtifactStore
from storage.grounding_outcomes import CACHE_DIR
from storage.runs import read_run_table
from tasks.grounding_eval import evaluate_grounding_run
from tests.small_store import write_small_store

SEQS = ("synth-000000", "synth-000001")


@pytest.fixture(scope="module")
def store_root(tmp_path_factory) -> str:
    root = tmp_path_factory.mktemp("grounding-cache")
    for seed in (0, 1):
        log = generate_log(seed, WorldConfig(num_frames=6, width=64, height=48))
        write_small_store(str(root), log, scene_hash=f"{seed:064x}", model_hash="0de1" + "0" * 60,
                          language_hash=f"{seed + 16:064x}")
    return str(root)


def _evaluate(root: str, seq_ids, name: str):
    result = evaluate_grounding_run.fn(root, list(seq_ids), root, f"runs/{name}")
    store = ArtifactStore(root)
    tables = {spec.name: read_run_table(store, f"runs/{name}", spec) for spec in (GROUNDING_SPEC, OUTCOMES_SPEC)}
    return result, tables, store.read_json(f"runs/{name}/manifest.json")


def _without_timings(table: pa.Table) -> pa.Table:
    return table.drop_columns([c for c in table.column_names if c == "seconds"])


def _clear_cache(root: str) -> None:
    ArtifactStore(root).delete(CACHE_DIR)


def test_a_run_evaluates_only_new_sequences_and_matches_a_fresh_evaluation(store_root: str) -> None:
    _clear_cache(store_root)
    fresh, fresh_tables, fresh_manifest = _evaluate(store_root, SEQS, "fresh")
    assert fresh_manifest["sequences_evaluated_this_run"] == list(SEQS) and fresh.queries > 0

    _clear_cache(store_root)
    _evaluate(store_root, SEQS[:1], "first")
    grown, grown_tables, grown_manifest = _evaluate(store_root, SEQS, "grown")
    assert grown_manifest["sequences_evaluated_this_run"] == [SEQS[1]]  # the first one's answers were kept
    assert grown.scores == fresh.scores and grown.queries == fresh.queries
    assert grown_tables["grounding"].equals(fresh_tables["grounding"])
    assert _without_timings(grown_tables["grounding_outcomes"]).equals(
        _without_timings(fresh_tables["grounding_outcomes"]))

    _, _, again = _evaluate(store_root, SEQS, "again")
    assert again["sequences_evaluated_this_run"] == []


def test_a_damaged_entry_is_named_and_recomputed(store_root: str, caplog) -> None:
    _evaluate(store_root, SEQS, "before-damage")
    entry = next(Path(store_root, CACHE_DIR, SEQS[1]).glob("*.parquet"))
    entry.write_bytes(b"PAR1 damaged")
    with caplog.at_level(logging.WARNING, logger="storage.grounding_outcomes"):
        _, _, manifest = _evaluate(store_root, SEQS, "after-damage")
    assert manifest["sequences_evaluated_this_run"] == [SEQS[1]]
    assert any(entry.name in r.getMessage() for r in caplog.records)


def test_a_change_to_the_code_recomputes_every_sequence(store_root: str, monkeypatch) -> None:
    _evaluate(store_root, SEQS, "before-change")
    monkeypatch.setattr("tasks.grounding_eval.source_digest", lambda *modules: "changed-code")
    _, _, manifest = _evaluate(store_root, SEQS, "after-change")
    assert manifest["sequences_evaluated_this_run"] == list(SEQS)
    assert [len(list(Path(store_root, CACHE_DIR, s).iterdir())) for s in SEQS] == [1, 1]  # old entries replaced
