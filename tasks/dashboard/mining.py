"""The mining pages: every run's edits table summed up (``/mining``), and one run's funnel, failure reasons,
attempts to acceptance, plausibility and its filterable scenario list (``/mining/<run_id>``).

    index = read_mining_index(store)                                  # MiningIndexView: one entry per edit run
    run = read_mining_run(store, "mine-0001", ScenarioFilters(category="remove"))

Everything is read from the run's edits table (``storage.edits.read_edit_records``) and reduced with
the evaluation's own definitions: proposals and their outcomes (``eval.mining.proposal_outcomes``), the funnel and
failure classes (``eval.mining_funnel``). A run of plain ``simsplat edit`` rows (no mining columns) is listed with
its row count and no funnel.
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from simsplat_core.eval.mining import ProposalOutcome, group_proposals, proposal_outcomes
from simsplat_core.eval.mining_funnel import FUNNEL_STAGES, FunnelRow, failure_classes, funnel_rows, stage_reached
from simsplat_core.mining.attempts import ATTEMPT_STATUSES
from simsplat_core.mining.vlm_protocol import PLAUSIBILITY_MAX, PLAUSIBILITY_MIN
from storage.edits import EditRecord, edit_run_ids, edits_table_relpath, read_edit_records
from storage.store import ArtifactStore
from tasks.dashboard.sections import Section, section


def edit_rows(records: Sequence[EditRecord]) -> list[dict[str, Any]]:
    """Edits-table records as row dicts: the edit's columns and the mining ones (absent ones ``None``)."""
    return [{"run_id": r.run_id, "seq_id": r.seq_id, "edit_id": r.edit_id, "attempt": r.attempt, "prompt": r.prompt,
             "command_json": r.command_json, "status": r.status, "failure_reason": r.failure_reason,
             **{k: r.mining.get(k) for k in ("mining_status", "scenario", "source", "category", "follows_prompt",
                                             "plausibility", "adjustment", "client", "judge_reasons")},
             "export": r.export} for r in records]


def _rows(store: ArtifactStore, run_id: str) -> list[dict[str, Any]]:
    return edit_rows(read_edit_records(store, run_id))


def is_mined(rows: Sequence[Mapping[str, Any]]) -> bool:
    """Whether every row carries the mining columns (a mining run, not plain ``simsplat edit`` rows)."""
    return bool(rows) and all(r.get("scenario") is not None and r.get("mining_status") for r in rows)


def _mean(values: Sequence[float]) -> float:
    return float(statistics.fmean(values)) if values else math.nan


# ----------------------------------------------------------------------------------------------- /mining
@dataclass(frozen=True)
class RunSummary:
    """One edit run at a glance.

    Attributes:
        mined: its rows carry the mining columns (else: plain edits, only ``attempts`` counted).
        client: the VLM client(s) that mined it.
        funnel: proposals passing each stage of ``stages`` (empty when not mined).
        completion: accepted / proposals (NaN: none); attempts_mean: mean attempt of acceptance (NaN: none);
        plausibility_mean: of the accepted (NaN: none).
    """

    run_id: str
    mined: bool
    client: str
    sequences: int
    attempts: int
    proposals: int
    accepted: int
    completion: float
    attempts_mean: float
    plausibility_mean: float
    funnel: tuple[int, ...] = ()


@dataclass(frozen=True)
class MiningIndexView:
    """Attributes: stages: the funnel's stages; runs: one section per edit run (an unreadable table says so)."""

    stages: tuple[str, ...]
    runs: Section[list[Section[RunSummary]]]


def _summary(run_id: str, rows: Sequence[Mapping[str, Any]]) -> RunSummary:
    sequences = len({r["seq_id"] for r in rows})
    if not is_mined(rows):
        return RunSummary(run_id, False, "", sequences, len(rows), 0, 0, math.nan, math.nan, math.nan)
    outcomes = proposal_outcomes("", rows)
    accepted = [o for o in outcomes if o.accepted]
    total = funnel_rows(rows)[-1]
    return RunSummary(
        run_id, True, ", ".join(sorted({str(r["client"]) for r in rows if r.get("client")})), sequences, len(rows),
        len(outcomes), len(accepted), len(accepted) / len(outcomes) if outcomes else math.nan,
        _mean([o.attempts for o in accepted]), _mean([o.plausibility for o in accepted if o.plausibility is not None]),
        total.proposals)


def read_mining_index(store: ArtifactStore) -> MiningIndexView:
    """Every edit run of ``store``, newest name first (each run's table read on its own: a corrupt one shows its
    error in its row)."""

    def runs() -> list[Section[RunSummary]]:
        return [section(f"run {run_id}", lambda run_id=run_id: _summary(run_id, _rows(store, run_id)))  # type: ignore[misc]
                for run_id in sorted(edit_run_ids(store), reverse=True)]

    return MiningIndexView(FUNNEL_STAGES, section("edit runs", runs))


# ----------------------------------------------------------------------------------------------- /mining/<run>
@dataclass(frozen=True)
class ScenarioFilters:
    """The scenario list's filters (``""`` / ``None``: any).

    Attributes:
        category: an edit category; status: the proposal's outcome (``accepted``, or the last attempt's status);
        min_plausibility: least judged plausibility of its last judged attempt; sequence: the log.
    """

    category: str = ""
    status: str = ""
    min_plausibility: int | None = None
    sequence: str = ""

    def keep(self, row: ScenarioRow) -> bool:
        return ((not self.category or row.category == self.category)
                and (not self.status or row.status == self.status)
                and (self.min_plausibility is None
                     or (row.plausibility is not None and row.plausibility >= self.min_plausibility))
                and (not self.sequence or row.seq_id == self.sequence))


@dataclass(frozen=True)
class ScenarioRow:
    """One proposal of the run (its card: ``/scenarios/<run>/<seq_id>/<edit_id>``).

    Attributes:
        status: ``accepted``, else the last attempt's mining status.
        stage: the furthest funnel stage its attempts reached.
        attempts: attempts made (for an accepted one: the attempt accepted).
        plausibility: the judge's score of its accepted attempt, else of its last judged one (``None``: never).
        reason: the last attempt's failure reason (``""`` when accepted).
    """

    seq_id: str
    edit_id: str
    scenario: int
    prompt: str
    category: str
    status: str
    stage: str
    attempts: int
    plausibility: int | None
    reason: str


@dataclass(frozen=True)
class FailureCount:
    """One failure class (``eval.mining_funnel.failure_classes``): attempts with it, and one of their reasons."""

    failure: str
    attempts: int
    example: str


@dataclass(frozen=True)
class Distribution:
    """Counts per value: ``values[k]`` seen ``counts[k]`` times (``accepted[k]`` of them accepted)."""

    values: tuple[int, ...]
    counts: tuple[int, ...]
    accepted: tuple[int, ...]


@dataclass(frozen=True)
class RunContent:
    """What one mining run's table shows (module docstring).

    Attributes:
        funnel: per edit category, then ``total``.
        failures: failure classes, most attempts first.
        attempts_to_acceptance: accepted proposals by the attempt that was accepted (1 = as first proposed).
        plausibility: judged attempts by plausibility (1..4), with how many of them were accepted.
        scenarios: the proposals passing the filters; total: proposals before filtering.
        categories, sequences: the values the filters offer.
    """

    summary: RunSummary
    funnel: list[FunnelRow]
    failures: list[FailureCount]
    attempts_to_acceptance: Distribution
    plausibility: Distribution
    scenarios: list[ScenarioRow]
    total: int
    categories: list[str]
    sequences: list[str]


@dataclass(frozen=True)
class MiningRunView:
    """Attributes: run_id; stages: the funnel's; statuses: the status filter's values; filters: those applied;
    content: the run's table reduced (its error when unreadable or not a mining run)."""

    run_id: str
    stages: tuple[str, ...]
    statuses: tuple[str, ...]
    filters: ScenarioFilters
    content: Section[RunContent] = field(default_factory=lambda: Section("edits table"))


def _failures(rows: Sequence[Mapping[str, Any]]) -> list[FailureCount]:
    counts: Counter[str] = Counter()
    example: dict[str, str] = {}
    for row in rows:
        for cls in failure_classes(str(row.get("failure_reason") or "")):
            counts[cls] += 1
            example.setdefault(cls, str(row["failure_reason"]))
    return [FailureCount(cls, n, example[cls]) for cls, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))]


def _distribution(values: Sequence[int], accepted: Sequence[bool], support: Sequence[int]) -> Distribution:
    every = sorted(set(support) | set(values))
    return Distribution(tuple(every), tuple(sum(v == x for v in values) for x in every),
                        tuple(sum(v == x and a for v, a in zip(values, accepted)) for x in every))


def _scenario_rows(rows: Sequence[Mapping[str, Any]], outcomes: Sequence[ProposalOutcome]) -> list[ScenarioRow]:
    out = []
    for outcome, attempts in zip(outcomes, group_proposals(rows).values()):
        shown = attempts[outcome.attempts - 1] if outcome.accepted else attempts[-1]
        judged = [r["plausibility"] for r in attempts[:outcome.attempts] if r.get("plausibility") is not None]
        stages = [FUNNEL_STAGES.index(stage_reached(r)) for r in attempts]
        out.append(ScenarioRow(
            seq_id=outcome.seq_id, edit_id=outcome.edit_id, scenario=outcome.scenario, prompt=str(shown["prompt"]),
            category=outcome.category, status="accepted" if outcome.accepted else str(shown["mining_status"]),
            stage=FUNNEL_STAGES[max(stages)], attempts=outcome.attempts,
            plausibility=int(judged[-1]) if judged else None, reason=str(shown["failure_reason"] or "")))
    return out


def _content(store: ArtifactStore, run_id: str, filters: ScenarioFilters) -> RunContent:
    rows = _rows(store, run_id)
    if not rows:
        raise FileNotFoundError(f"{store.uri(edits_table_relpath(run_id))}: no edits table (or no rows)")
    if not is_mined(rows):
        raise ValueError(f"run {run_id!r} holds plain edits (no mining columns): it has no funnel")
    outcomes = proposal_outcomes("", rows)
    scenarios = _scenario_rows(rows, outcomes)
    judged = [r for r in rows if r.get("plausibility") is not None]
    accepted = [o for o in outcomes if o.accepted]
    return RunContent(
        summary=_summary(run_id, rows), funnel=funnel_rows(rows), failures=_failures(rows),
        attempts_to_acceptance=_distribution([o.attempts for o in accepted], [True] * len(accepted), [1]),
        plausibility=_distribution([int(r["plausibility"]) for r in judged],
                                   [r["mining_status"] == "accepted" for r in judged],
                                   range(PLAUSIBILITY_MIN, PLAUSIBILITY_MAX + 1)),
        scenarios=[s for s in scenarios if filters.keep(s)], total=len(scenarios),
        categories=sorted({s.category for s in scenarios}), sequences=sorted({s.seq_id for s in scenarios}))


def read_mining_run(store: ArtifactStore, run_id: str, filters: ScenarioFilters | None = None) -> MiningRunView:
    """One mining run (module docstring); ``filters`` narrow its scenario list only (the funnel and the
    distributions are the whole run's)."""
    filters = filters or ScenarioFilters()
    return MiningRunView(run_id, FUNNEL_STAGES, ATTEMPT_STATUSES, filters,
                         section("edits table", lambda: _content(store, run_id, filters)))


def run_exists(store: ArtifactStore, run_id: str) -> bool:
    """Whether ``edits/<run_id>`` is in the store (a safe name only)."""
    return bool(run_id) and "/" not in run_id and not run_id.startswith(".") and store.is_dir(f"edits/{run_id}")


__all__ = ["Distribution", "FailureCount", "MiningIndexView", "MiningRunView", "RunContent", "RunSummary",
           "ScenarioFilters", "ScenarioRow", "edit_rows", "is_mined", "read_mining_index", "read_mining_run",
           "run_exists"]
