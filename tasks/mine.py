"""Mine one stored sequence for scenarios and store them (what ``simsplat mine`` runs per sequence).

Thin: load the sequence's edit context (``tasks.stored_edits.load_edit_context``), build the VLM client (the rule-based
one of the seed, or the OpenAI-compatible one from ``SIMSPLAT_VLM_URL`` / ``SIMSPLAT_VLM_MODEL`` /
``SIMSPLAT_VLM_API_KEY``), call ``simsplat_core.mining.mine_sequence``, then store:

* every accepted scenario as an edit directory ``edits/<run_id>/<seq_id>/<edit_id>/``, exactly as ``simsplat edit``
  writes one (``tasks.stored_edits.write_edit``; a scenario already stored under the same key is not re-rendered);
* one row per attempt in the run's ``edits`` table, all rows of the sequence appended in one atomic rewrite
  (``storage.edits.append_edit_records``), with the mining columns (``mining_status``, ``category``,
  ``plausibility``, ``export``, stage seconds, the judge's reasons in ``judge_reasons``, ...);
* when the run keeps a mining ledger, after both: the sequence's ledger record (``tasks.mining_ledger``).

Inside a Prefect run it publishes a progress artifact (accepted / wanted) while mining and a table artifact of the
accepted scenarios at the end; called as ``mine_sequence_task.fn(...)`` it is a plain function.
"""

from __future__ import annotations

import dataclasses
import logging
import re
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.compute_threads import set_compute_threads
from simsplat_core.editing.commands import program_from_json
from simsplat_core.mining.attempts import EDITS_COLUMNS, AttemptRecord, attempt_rows
from simsplat_core.mining.loop import MiningConfig, default_client, mine_sequence
from simsplat_core.mining.rule_proposals import Proposal
from simsplat_core.mining.vlm_protocol import VLMClient
from simsplat_core.vlm.openai_chat import OpenAIChatConfig
from storage import ArtifactStore, intact_marker
from storage.edits import EditRecord, append_edit_records, compact_edit_records, edit_dir, edits_table_relpath
from storage.inventory import require_asset_bank
from storage.schemas.edits import EDITS_MINING_COLUMNS
from tasks.mining_ledger import LedgerSettings, MinedSequence, record_mined
from tasks.progress import StepProgress, publish_rows
from tasks.retry_policy import STAGE_RETRIES
from tasks.stored_edits import LoadedEdit, edit_key, load_edit_context, write_edit

logger = logging.getLogger(__name__)

#: ``--vlm`` choices.
VLM_KINDS: tuple[str, ...] = ("rule", "openai")


@dataclass(frozen=True)
class MinedScenario:
    """One accepted (exported) scenario: where it is stored and how it was found.

    Attributes:
        attempts: the attempt of its scenario that was accepted (1 = as first proposed).
        plausibility: the judge's plausibility (``None`` when not judged).
        edit_dir: URI of the stored edit directory.
    """

    seq_id: str
    edit_id: str
    prompt: str
    category: str
    attempts: int
    plausibility: int | None
    edit_dir: str


@dataclass(frozen=True)
class MiningSummary:
    """What :func:`mine_sequence_task` did in one sequence.

    Attributes:
        attempts: attempts made (rows appended); accepted: scenarios accepted and stored.
        statuses: attempts per mining status (accepted / rejected / refused / failed).
        per_category: accepted scenarios per edit category.
        seconds: per stage (``load``, ``propose``, ``command``, ``edit``, ``render`` (the judge's views),
            ``judge``, ``store_render`` (every frame and camera of the accepted scenarios, as ``simsplat edit``
            stores them), ``write`` (encoding and files), ``total``), and the editor's split of ``edit``
            (``ground``, ``apply``, ``refine``, ``validate``).
        edits_table: URI of the run's edits table.
        scenarios: the accepted scenarios, in order.
    """

    seq_id: str
    run_id: str
    client: str
    attempts: int
    accepted: int
    statuses: dict[str, int] = field(default_factory=dict)
    per_category: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    edits_table: str = ""
    scenarios: tuple[MinedScenario, ...] = ()


def make_client(vlm: str, loaded: LoadedEdit, config: MiningConfig, chat: OpenAIChatConfig | None = None
                ) -> VLMClient:
    """The mining client: ``"rule"`` (the rule-based client of ``config.seed``) or ``"openai"`` (``chat``, else from
    the environment; the key is read from the variable ``chat.api_key_env`` names and never logged).

    Raises:
        ValueError: an unknown ``vlm``; VLMError: ``"openai"`` without an endpoint configured.
    """
    if vlm == "rule":
        return default_client(loaded.ctx, config)
    if vlm == "openai":
        from simsplat_core.mining.openai_vlm import OpenAIVLMClient
        from simsplat_core.vlm.openai_chat import OpenAIChatClient

        return OpenAIVLMClient(OpenAIChatClient(chat or OpenAIChatConfig.from_env()))
    raise ValueError(f"unknown VLM client {vlm!r}; choose one of {list(VLM_KINDS)}")


def _edit_record(row: dict[str, Any]) -> EditRecord:
    """An attempt row (``mining.attempts.attempt_row``) as an :class:`EditRecord` (numbered when appended)."""
    edit = {k: row[k] for k in EDITS_COLUMNS if k not in EDITS_MINING_COLUMNS and k != "attempt"}
    return EditRecord(**edit, mining={k: row[k] for k in EDITS_MINING_COLUMNS})


def _unstored(record: EditRecord, exc: Exception) -> EditRecord:
    """The row of an accepted attempt whose edit could not be stored: failed, not exported."""
    return dataclasses.replace(record, status="failed", failure_reason=f"error: {type(exc).__name__}: {exc}",
                               mining={**record.mining, "mining_status": "failed", "export": False})


def _store_accepted(store: ArtifactStore, loaded: LoadedEdit, config: MiningConfig, attempt: AttemptRecord,
                    record: EditRecord, seconds: dict[str, float]) -> str:
    """Write the edit directory of an accepted attempt (unless stored under the same key); returns its URI."""
    assert attempt.edited is not None
    program = program_from_json(attempt.program_json, source=f"mined scenario {attempt.edit_id}")
    key = edit_key(loaded, attempt.prompt, program, config.options)
    rel = edit_dir(record.run_id, record.seq_id, record.edit_id)
    if intact_marker(store, rel, key) is not None:
        logger.info("%s: scenario %s already stored, skipping", record.seq_id, record.edit_id)
        return store.uri(rel)
    timing: dict[str, float] = {}
    write_edit(store, record, key, loaded, program, attempt.edited, timing, append=False)
    seconds["store_render"] = seconds.get("store_render", 0.0) + timing.get("render", 0.0)
    seconds["write"] = seconds.get("write", 0.0) + sum(timing.values()) - timing.get("render", 0.0)
    return store.uri(rel)


def _artifact_key(seq_id: str) -> str:
    return "mining-" + (re.sub(r"[^a-z0-9-]+", "-", seq_id.lower()).strip("-") or "sequence")


@task(name="mine-sequence", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def mine_sequence_task(store_root: str, seq_id: str, run_id: str, *, per_sequence: int = 3, max_attempts: int = 3,  # noqa: PLR0913 -- Prefect task: its parameters are the run's inputs (options keyword-only)
                       vlm: str = "rule", seed: int = 0, seed_prompts: Sequence[str | Proposal] = (),
                       client: VLMClient | None = None, category_offset: int | None = None,
                       categories: tuple[str, ...] = (), chat: OpenAIChatConfig | None = None,
                       threads: int = 0, ledger: LedgerSettings | None = None) -> MiningSummary:
    """Mine ``seq_id`` for ``per_sequence`` accepted scenarios (``max_attempts`` per proposal) and store them
    under run ``run_id`` (module docstring). ``client`` replaces the one ``vlm`` names (e.g. a rule-based client
    with another judge configuration). ``category_offset``: where the sequence starts in the run's order of edit
    categories (``MiningConfig.category_offset``; a run passes ``i * per_sequence`` for its ``i``-th sequence).
    ``categories``: the edit categories wanted (``MiningConfig.categories``; empty: all). ``chat``: the
    OpenAI-compatible endpoint of ``vlm="openai"`` (``None``: from the environment). ``threads``: torch/numba
    threads for this task (0 = leave the process setting). ``ledger``: the run's mining settings; once the
    sequence's edits and rows are stored, the mining ledger records it as mined with them (``tasks.mining_ledger``;
    ``None``: not recorded).

    Raises:
        FileNotFoundError: the store lacks the sequence's log, language scene, or (for a log with images) an asset
            bank (naming the store and what to run).
        VLMError: ``vlm="openai"`` without an endpoint configured.
    """
    started = time.perf_counter()
    if threads:
        set_compute_threads(threads)
    store = ArtifactStore(store_root)
    loaded = load_edit_context(store, seq_id)
    if loaded.renders:  # a log without images inserts boxes (tasks.stored_edits)
        require_asset_bank(store, f"to mine {seq_id!r} with")
    config = MiningConfig(scenarios=per_sequence, max_attempts=max_attempts, seed=seed,
                          category_offset=category_offset, categories=tuple(categories))
    client = client if client is not None else make_client(vlm, loaded, config, chat)
    logger.info("%s: mining %d scenario(s) with %s (max %d attempts each, seed %d)", seq_id, per_sequence,
                client.name, max_attempts, seed)
    step = StepProgress(f"mine {seq_id}", headline="")
    result = mine_sequence(loaded.ctx, client, config, seed_prompts=tuple(seed_prompts),
                           progress=lambda accepted, wanted: step(accepted, wanted))
    seconds = {"load": loaded.seconds, **{k: float(v) for k, v in result.seconds.items()}, "store_render": 0.0,
               "write": 0.0}

    records: list[EditRecord] = []
    scenarios: list[MinedScenario] = []
    error: Exception | None = None
    for attempt, row in zip(result.records, attempt_rows(result, run_id)):
        record = _edit_record(row)
        if attempt.status == "accepted":
            if error is None:
                try:
                    uri = _store_accepted(store, loaded, config, attempt, record, seconds)
                    scenarios.append(MinedScenario(seq_id, attempt.edit_id, attempt.prompt, attempt.category,
                                                   attempt.attempt, attempt.plausibility, uri))
                except Exception as exc:  # recorded as failed with the other attempts' rows, then raised
                    error = exc
            if error is not None:  # this one or an earlier accepted one could not be stored
                record = _unstored(record, error)
        records.append(record)
    append_edit_records(store, records)
    if error is not None:
        raise error
    if ledger is not None:
        record_mined(store, ledger, MinedSequence(seq_id, run_id, loaded.log_key, loaded.scene_hash,
                                                  loaded.language_hash, len(result.records),
                                                  tuple((s.edit_id, s.prompt, s.category) for s in scenarios)))
    step(per_sequence, per_sequence)  # the last report: done, whatever was accepted
    seconds["total"] = time.perf_counter() - started

    table = [{"prompt": s.prompt, "category": s.category, "attempts": s.attempts, "plausibility": s.plausibility,
              "edit_dir": s.edit_dir} for s in scenarios]
    publish_rows(table, _artifact_key(seq_id), f"Scenarios mined in {seq_id} (run {run_id}, {client.name})")
    summary = MiningSummary(
        seq_id=seq_id, run_id=run_id, client=client.name, attempts=len(result.records), accepted=len(scenarios),
        statuses=dict(Counter(r.status for r in result.records)),
        per_category=dict(Counter(s.category for s in scenarios)), seconds=seconds,
        edits_table=store.uri(edits_table_relpath(run_id)), scenarios=tuple(scenarios))
    logger.info("%s: %d attempt(s), %d accepted (%s)", seq_id, summary.attempts, summary.accepted, summary.statuses)
    return summary


def compact_mining_run(store_root: str, run_id: str) -> int:
    """Fold the run's edits parts (one per mined sequence) into one once its mining tasks are done; called by the
    run's single driver. Returns how many parts were folded."""
    return compact_edit_records(ArtifactStore(store_root), run_id)


@task(name="saved-search-seeds", retries=0, cache_policy=NO_CACHE)
def saved_search_seeds_task(store_root: str, queries: Sequence[str], *, sequences: list[str] | None = None,
                            per_hit: int = 2) -> dict[str, list[Proposal]]:
    """Per sequence, the seed proposals of a mining configuration's saved searches (``tasks.search.saved_search_seeds``:
    ``per_hit`` variants of each hit's subject), for :func:`mine_sequence_task`'s ``seed_prompts``."""
    from tasks.search import saved_search_seeds

    return saved_search_seeds(store_root, queries, sequences=sequences, per_hit=per_hit)


__all__ = ["VLM_KINDS", "MinedScenario", "MiningSummary", "make_client", "mine_sequence_task",
           "saved_search_seeds_task"]
