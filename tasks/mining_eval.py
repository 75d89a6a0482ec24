"""Task: evaluate scenario mining on the stored sequences (SIMSplat Table 5 analogue, throughput).

Thin: per VLM client (``rule``; ``openai`` only when an endpoint is configured, else its row says it was not run),
mine every sequence under a fresh run id (``tasks.mine.mine_sequence_task``: accepted scenarios are stored as
edits under ``edits/<run_id>/``, every attempt is a row of that run's edits table; the stored scenes are never
written), read the run's edits table back, re-check every accepted scenario from its STORED
``trajectories.parquet`` (``simsplat_core.eval.mining.stored_failure``), and write into ``OUT``:
``tables/mining.{parquet,md}`` (one row per client), ``tables/mining_by_category``, ``tables/mining_stages`` (where
the time goes, accepted scenarios per hour per core) and ``manifest.json``. Definitions of the measures:
``simsplat_core.eval.mining``.

The search benchmark plugs in through ``search_table`` (``tasks.search_eval``'s table of the query set: timestamp
and log balanced accuracy), written beside the mining tables as ``tables/search.{parquet,md}``.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.compute_threads import compute_threads
from simsplat_core.eval.mining import (
    MINING_BY_CATEGORY_SPEC,
    MINING_SPEC,
    MINING_STAGES,
    MINING_STAGES_SPEC,
    ProposalOutcome,
    collides_or_offroad,
    mining_by_category_table,
    mining_stages_table,
    mining_table,
    proposal_outcomes,
    stored_failure,
)
from simsplat_core.mining.vlm_protocol import VLMClient
from simsplat_core.vlm.openai_chat import OpenAIChatConfig, VLMError
from storage import ArtifactStore
from storage.edits import read_edit_delta, read_edit_records, read_trajectories
from storage.runs import RunTable, new_run_id, run_table, write_run_tables
from tasks.mine import VLM_KINDS, MiningSummary, mine_sequence_task
from tasks.stored_edits import LoadedEdit, load_edit_context

logger = logging.getLogger(__name__)

#: The search benchmark's hook: ``search_table(store_root, seq_ids)`` -> its ``search`` table (written as
#: ``tables/search.{parquet,md}`` with the mining tables), or ``None`` when it has nothing to add.
SearchTable = Callable[[str, Sequence[str]], RunTable | None]


@dataclass(frozen=True)
class MiningEvaluation:
    """What :func:`evaluate_mining_run` returns (small).

    Attributes:
        seq_ids: the mined sequences.
        runs: client -> run id of its mining run (``edits/<run_id>/`` in the store); clients not run are absent.
        mining: the ``mining`` table's rows (one per client).
        by_category: the ``mining_by_category`` table's rows.
        stages: the ``mining_stages`` table's rows.
        failed_scenarios: ``"<client> <seq_id> <edit_id>: <failed agents>"`` of accepted scenarios that collide or
            leave the road on re-check.
        tables: name -> Parquet URI.
        cores: cores the throughput is counted on.
        seconds: wall time of the whole evaluation.
    """

    seq_ids: tuple[str, ...]
    runs: dict[str, str]
    mining: list[dict[str, Any]]
    by_category: list[dict[str, Any]]
    stages: list[dict[str, Any]]
    failed_scenarios: list[str]
    tables: dict[str, str]
    cores: int
    seconds: float


def client_unavailable(client: str) -> str:
    """Why ``client`` cannot run here (``""``: it can): ``openai`` without ``SIMSPLAT_VLM_URL`` /
    ``SIMSPLAT_VLM_MODEL``.

    Raises:
        ValueError: an unknown client name.
    """
    if client not in VLM_KINDS:
        raise ValueError(f"unknown VLM client {client!r}; choose among {list(VLM_KINDS)}")
    if client == "openai":
        try:
            OpenAIChatConfig.from_env()
        except VLMError as exc:
            return f"not run: {exc}"
    return ""


def _recheck(store: ArtifactStore, loaded: LoadedEdit, run_id: str, seq_id: str, edit_id: str) -> tuple[bool, str]:
    """Whether the stored scenario ``edit_id`` collides or leaves the road, and its failed agents."""
    sizes: dict[str, tuple[float, float, float]] = {}
    bank = loaded.ctx.bank
    for added in read_edit_delta(store, run_id, seq_id, edit_id).delta.added:
        if bank is None:
            raise FileNotFoundError(f"{store.uri('assets')}: no asset bank to size the inserted {added.object_id}")
        sizes[added.object_id] = bank.get(added.asset_id).size
    failure = stored_failure(read_trajectories(store, run_id, seq_id, edit_id), loaded.ctx.states, sizes,
                             loaded.ctx.map_ctx)
    return collides_or_offroad(failure), ", ".join(failure.failed_agents)


@task(name="evaluate-mining", retries=0, cache_policy=NO_CACHE)
def evaluate_mining_run(store_root: str, seq_ids: Sequence[str], out_root: str, out_relpath: str = "", *,  # noqa: PLR0913 -- Prefect task: its parameters are the run's inputs (options keyword-only)
                        clients: Sequence[str] = ("rule",), per_sequence: int = 3, max_attempts: int = 3,
                        seed: int = 0, cores: int | None = None, search_table: SearchTable | None = None,
                        client_overrides: Mapping[str, VLMClient] | None = None) -> MiningEvaluation:
    """Mine ``seq_ids`` with each of ``clients`` and write the mining tables into ``out_root`` (module docstring).

    Args:
        per_sequence: accepted scenarios wanted per sequence (K); max_attempts: attempts per proposal.
        cores: cores the throughput is counted on (default: this process's compute threads, at most the CPUs).
        search_table: the search benchmark's hook (:data:`SearchTable`; ``None``: no ``search`` table).
        client_overrides: clients replacing the ones named (e.g. a rule-based client with another judge
            configuration), by name.

    Raises:
        ValueError: no sequence, or an unknown client.
        FileNotFoundError: a log, language scene or the asset bank is missing (named).
    """
    if not seq_ids:
        raise ValueError("evaluate_mining_run: no sequences to mine")
    notes = {client: client_unavailable(client) for client in dict.fromkeys(clients)}
    started = time.perf_counter()
    cores = cores or max(1, min(compute_threads().torch, os.cpu_count() or 1))
    store = ArtifactStore(store_root)
    loaded: dict[str, LoadedEdit] = {}
    outcomes: list[ProposalOutcome] = []
    failures: dict[tuple[str, str, str], bool] = {}
    failed: list[str] = []
    runs: dict[str, str] = {}
    seconds: dict[str, dict[str, float]] = {}
    accepted: dict[str, int] = {}
    for client, note in notes.items():
        if note:
            logger.info("mining eval: client %s %s", client, note)
            continue
        run_id = runs[client] = new_run_id(f"evalmine-{client}")
        summaries: list[MiningSummary] = [
            mine_sequence_task.fn(store_root, seq_id, run_id, per_sequence=per_sequence, max_attempts=max_attempts,
                                  vlm=client, seed=seed, client=(client_overrides or {}).get(client),
                                  category_offset=i * per_sequence)
            for i, seq_id in enumerate(seq_ids)]
        seconds[client] = {s: sum(m.seconds.get(s, 0.0) for m in summaries) for s in MINING_STAGES}
        accepted[client] = sum(m.accepted for m in summaries)
        rows = [{"seq_id": r.seq_id, "edit_id": r.edit_id, **r.mining} for r in read_edit_records(store, run_id)]
        mine = proposal_outcomes(client, rows)
        outcomes += mine
        for o in (o for o in mine if o.accepted):
            if o.seq_id not in loaded:
                loaded[o.seq_id] = load_edit_context(store, o.seq_id)
            bad, agents = _recheck(store, loaded[o.seq_id], run_id, o.seq_id, o.edit_id)
            failures[(client, o.seq_id, o.edit_id)] = bad
            if bad:
                failed.append(f"{client} {o.seq_id} {o.edit_id}: {agents}")
    mining = mining_table(outcomes, failures, notes)
    by_category = mining_by_category_table(outcomes, [c for c, note in notes.items() if not note])
    stages = mining_stages_table(seconds, accepted, cores)
    tables = {spec.name: run_table(spec, table) for spec, table in (
        (MINING_SPEC, mining), (MINING_BY_CATEGORY_SPEC, by_category), (MINING_STAGES_SPEC, stages))}
    if search_table is not None:  # tasks.search_eval plugs in here
        search = search_table(store_root, seq_ids)
        if search is not None:
            tables["search"] = search
    manifest = {"stage": "mining", "sequences": list(seq_ids), "clients": notes, "runs": runs,
                "per_sequence": per_sequence, "max_attempts": max_attempts, "seed": seed, "cores": cores,
                "failed_scenarios": failed, "seconds": round(time.perf_counter() - started, 3)}
    uris = write_run_tables(ArtifactStore(out_root), out_relpath, tables, manifest)
    seconds_all = time.perf_counter() - started
    logger.info("mining eval on %d sequence(s): %s (%.0f s)", len(seq_ids), "; ".join(
        f"{r['client']} {r['accepted']}/{r['prompts']}" for r in mining.to_pylist()), seconds_all)
    return MiningEvaluation(tuple(seq_ids), runs, mining.to_pylist(), by_category.to_pylist(), stages.to_pylist(),
                            failed, uris, cores, round(seconds_all, 3))


__all__ = ["MiningEvaluation", "SearchTable", "client_unavailable", "evaluate_mining_run"]
