"""The mining loop's records: one :class:`AttemptRecord` per attempt, a sequence's :class:`MiningResult`, and the
rows of the ``edits`` table they make.

    result = mine_sequence(ctx, client, config)            # mining.loop
    result.accepted                                         # the attempts marked for export (their .edited kept)
    rows = attempt_rows(result, run_id="mine-0001")         # dicts: the edits table's columns + mining extras

Statuses: ``"accepted"`` (executed, valid, and the judge says it follows the prompt plausibly: exported),
``"rejected"`` (executed, but a validation failure or the judge turned it down), ``"refused"`` (the prompt could
not be turned into commands, or the editor refused the commands: ``EditRefused``) and ``"failed"`` (the VLM
failed or answered malformed: ``VLMError``, or an invalid answer).

``failure_reason`` is ``"<reason>: <message>"`` as in the ``edits`` table: a refusal's ``EditRefused.reason``,
``"rejected"`` followed by the validation failures and the judge's verdict and reasons, ``"vlm_error"`` for a
failed call (naming the stage). Records compare on what was decided, not on timings or the edited scene, so two
runs with the same seed give equal records.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, get_args

from simsplat_core.editing.result import EDIT_STAGES, EditedScene
from simsplat_core.mining.vlm_protocol import Judgement

AttemptStatus = Literal["accepted", "rejected", "refused", "failed"]
ATTEMPT_STATUSES: tuple[str, ...] = get_args(AttemptStatus)
#: Stages timed per attempt (seconds): proposing, turning the prompt into commands, the edit (ground, apply,
#: refine, validate), rendering the judge's views and the BEV, judging.
STAGES: tuple[str, ...] = ("propose", "command", "edit", "render", "judge")
#: Every timed stage of an attempt: :data:`STAGES` (the ``edits`` table's ``seconds_<stage>`` columns) and the
#: editor's split of ``edit`` (``editing.result.EDIT_STAGES``: ground, apply, refine, validate; 0 for an edit
#: refused before it finished).
TIMED_STAGES: tuple[str, ...] = (*STAGES, *EDIT_STAGES)
#: ``edits.status`` of each attempt status (the table knows ``succeeded`` / ``refused`` / ``failed``; a rejected
#: attempt ran but is not kept: ``failed``, its ``failure_reason`` starting with ``rejected:``).
TABLE_STATUS: dict[str, str] = {"accepted": "succeeded", "rejected": "failed", "refused": "refused", "failed": "failed"}
#: Columns of the ``edits`` table (``storage.schemas.EDITS_SCHEMA``, version 3), in its order: the edit's, then
#: the mining columns (:func:`attempt_row`'s extras).
EDITS_COLUMNS: tuple[str, ...] = ("run_id", "seq_id", "edit_id", "attempt", "prompt", "command_json", "status",
                                  "failure_reason", "mining_status", "scenario", "source", "category",
                                  "follows_prompt", "plausibility", "adjustment", "export", "client",
                                  *(f"seconds_{stage}" for stage in STAGES), "judge_reasons")


def scenario_key(seq_id: str, seed: int, scenario: int, prompt: str) -> str:
    """The ``edit_id`` of one mined scenario (shared by its attempts; the table numbers them): 16 hex digits of a
    hash of the sequence, the loop's seed, the scenario's index and its prompt."""
    text = "\x1f".join(("mine", seq_id, str(int(seed)), str(int(scenario)), prompt))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclass(frozen=True)
class AttemptRecord:
    """One attempt of the mining loop (a row of the ``edits`` table).

    Attributes:
        seq_id: the sequence.
        scenario: index of the proposal in the sequence (0-based; its attempts share it and ``edit_id``).
        attempt: 1 for the proposal as asked, then 2, 3, ... for the adjusted retries.
        edit_id: :func:`scenario_key` of the scenario.
        prompt: the prompt executed (a retry keeps the words; its program changed).
        source: ``"seed"`` (a seed prompt, e.g. a search hit) or ``"client"`` (the VLM client proposed it).
        category: one of the six edit categories (``rule_proposals.EDIT_CATEGORIES``; ``""`` when neither the
            proposal nor a program tells).
        program_json: the executed program as JSON (``""`` when none was made).
        status: one of :data:`ATTEMPT_STATUSES` (module docstring).
        failure_reason: ``"<reason>: <message>"`` (``""`` when accepted).
        follows_prompt, plausibility: the judge's answers (``None`` when not judged).
        judgement: the whole verdict (``None`` when not judged).
        adjustment: what changed from the previous attempt (``""`` for the first).
        seconds: per stage of :data:`TIMED_STAGES` (not compared).
        edited: the edited scene of an accepted attempt, kept in memory for the caller to store (else ``None``;
            not compared, not in the repr).
    """

    seq_id: str
    scenario: int
    attempt: int
    edit_id: str
    prompt: str
    source: str
    category: str
    program_json: str
    status: AttemptStatus
    failure_reason: str = ""
    follows_prompt: bool | None = None
    plausibility: int | None = None
    judgement: Judgement | None = None
    adjustment: str = ""
    seconds: Mapping[str, float] = field(default_factory=dict, compare=False, hash=False)
    edited: EditedScene | None = field(default=None, compare=False, repr=False, hash=False)

    def __post_init__(self) -> None:
        if self.status not in ATTEMPT_STATUSES:
            raise ValueError(f"AttemptRecord.status must be one of {ATTEMPT_STATUSES}, got {self.status!r}")
        if (self.status == "accepted") == bool(self.failure_reason):
            raise ValueError("AttemptRecord.failure_reason must be empty exactly when the attempt is accepted")
        if self.attempt < 1:
            raise ValueError(f"AttemptRecord.attempt is 1-based, got {self.attempt}")
        object.__setattr__(self, "seconds", {k: float(v) for k, v in self.seconds.items()})

    @property
    def export(self) -> bool:
        """Marked for export (the ``export`` column): the attempt was accepted."""
        return self.status == "accepted"


@dataclass(frozen=True)
class MiningResult:
    """What :func:`~simsplat_core.mining.loop.mine_sequence` did in one sequence.

    Attributes:
        seq_id: the sequence; client: the VLM client's ``name``.
        records: every attempt, in order.
        prompts: the proposals taken, in order (seed prompts first).
        seconds: total seconds per stage of :data:`TIMED_STAGES` (``propose`` includes the scene facts and the
            proposal views), not compared.
    """

    seq_id: str
    client: str
    records: tuple[AttemptRecord, ...]
    prompts: tuple[str, ...] = ()
    seconds: Mapping[str, float] = field(default_factory=dict, compare=False, hash=False)

    @property
    def accepted(self) -> tuple[AttemptRecord, ...]:
        """The accepted attempts (marked for export), in order."""
        return tuple(r for r in self.records if r.status == "accepted")

    def count(self, status: str) -> int:
        """Attempts with ``status``."""
        return sum(r.status == status for r in self.records)


def attempt_row(record: AttemptRecord, run_id: str, client: str = "") -> dict[str, Any]:
    """``record`` as one row of the ``edits`` table (:data:`EDITS_COLUMNS`; ``status`` mapped by
    :data:`TABLE_STATUS`, the attempt's own status in ``mining_status``): the edit's columns and the mining ones
    ``mining_status``, ``scenario``, ``source``, ``category``,
    ``follows_prompt``, ``plausibility``, ``adjustment``, ``export``, ``client``, ``seconds_<stage>`` and
    ``judge_reasons`` (:func:`judge_reasons_json`)."""
    row: dict[str, Any] = {
        "run_id": run_id, "seq_id": record.seq_id, "edit_id": record.edit_id, "attempt": record.attempt,
        "prompt": record.prompt, "command_json": record.program_json, "status": TABLE_STATUS[record.status],
        "failure_reason": record.failure_reason,
        "mining_status": record.status, "scenario": record.scenario, "source": record.source,
        "category": record.category, "follows_prompt": record.follows_prompt, "plausibility": record.plausibility,
        "adjustment": record.adjustment, "export": record.export, "client": client,
    }
    row.update({f"seconds_{stage}": float(record.seconds.get(stage, 0.0)) for stage in STAGES})
    row["judge_reasons"] = judge_reasons_json(record.judgement)
    return row


def judge_reasons_json(verdict: Judgement | None) -> str | None:
    """The ``judge_reasons`` column: the verdict's reasons as a JSON list of strings (``None``: not judged)."""
    return None if verdict is None else json.dumps(list(verdict.reasons), ensure_ascii=False)


def judge_reasons_of(text: str | None) -> tuple[str, ...]:
    """The reasons of a ``judge_reasons`` value (``()`` for ``None``: not judged, or a table written before the
    column).

    Raises:
        ValueError: ``text`` is not a JSON list of strings (quoting it).
    """
    if text is None:
        return ()
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"judge_reasons {text[:80]!r}: not JSON ({exc})") from exc
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ValueError(f"judge_reasons {text[:80]!r}: not a JSON list of strings")
    return tuple(value)


def attempt_rows(result: MiningResult, run_id: str) -> list[dict[str, Any]]:
    """Every attempt of ``result`` as :func:`attempt_row`, in order."""
    return [attempt_row(r, run_id, result.client) for r in result.records]


__all__ = ["ATTEMPT_STATUSES", "EDITS_COLUMNS", "STAGES", "TABLE_STATUS", "TIMED_STAGES", "AttemptRecord",
           "AttemptStatus", "MiningResult", "attempt_row", "attempt_rows", "judge_reasons_json", "judge_reasons_of",
           "scenario_key"]
