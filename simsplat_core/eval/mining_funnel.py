"""The mining funnel: how far each attempt and proposal of a mining run got, and why the others stopped, read from
the run's ``edits``-table rows (``mining.attempts.attempt_row``: ``mining_status``, ``failure_reason``,
``command_json``, ``follows_prompt``).

    stage_reached(row)                   # "proposed" .. "accepted": the last stage the attempt passed
    failure_classes(row["failure_reason"])  # ("rejected: collision", "rejected: implausible"), ("not_found",), ...
    rows = funnel_rows(edits_rows)       # per edit category, then "total": proposals reaching each stage

Stages (:data:`FUNNEL_STAGES`), each passed by an attempt that passed the one before:

* ``proposed``: every attempt (a failed proposing or translating call, a prompt the client refused to turn into
  commands, a program failing the schema stop here);
* ``grounded``: a program was made and its targets and anchors matched objects (an editor refusal other than
  ``not_found`` -- no asset, an infeasible placement or motion, ... -- stops here);
* ``edited``: the editor produced the edited scene (a validation failure, or a judge call that failed, stops
  here: the edit's validation is not known then);
* ``validated``: no collision, off-road agent or infeasible motion;
* ``judged``: the judge answered (a verdict that does not follow the prompt or is too implausible, or an accepted
  scenario that could not be stored, stops here);
* ``accepted``: kept for export.

A proposal's stage is the furthest any of its attempts got (``eval.mining.group_proposals``). The
``failure_reason`` grammar is the loop's (``mining.loop``: ``"<refusal reason>: ..."``, ``"vlm_error: <stage>:
..."``, ``"rejected: validation: ... | judge: ..."``) and the store task's (``"error: ..."``: storing failed).
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from simsplat_core.eval.mining import UNKNOWN_CATEGORY, group_proposals
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES

#: The funnel's stages, in order (module docstring).
FUNNEL_STAGES: tuple[str, ...] = ("proposed", "grounded", "edited", "validated", "judged", "accepted")
#: Where a rejection lists the validation's failures (``mining.loop.rejection_reason``).
VALIDATION_MARK = "validation: "
#: Failure kinds of the validation's text (``scenario.metrics.AgentValidation.failures``): phrase -> kind.
VALIDATION_PHRASES: dict[str, str] = {"collides with": "collision", "leaves the drivable area": "offroad",
                                      "moves infeasibly": "kinematic"}
#: Refusals that stop an attempt before its targets are grounded.
UNGROUNDED_REFUSALS: frozenset[str] = frozenset({"not_found", "invalid_command"})
_PLAUSIBILITY = re.compile(r"plausibility (\d+)/\d+ \(least (\d+)\)")


def reason_code(reason: str) -> str:
    """The code a ``failure_reason`` starts with (``"not_found"``, ``"rejected"``, ``"vlm_error"``, ...; ``""``
    for none)."""
    return reason.split(":", 1)[0].strip() if reason else ""


def stage_reached(row: Mapping[str, Any]) -> str:
    """The last stage of :data:`FUNNEL_STAGES` one attempt passed (module docstring), from its edits-table row."""
    if row.get("mining_status") == "accepted":
        return "accepted"
    reason = str(row.get("failure_reason") or "")
    code = reason_code(reason)
    if row.get("mining_status") == "rejected" or row.get("follows_prompt") is not None:
        return "edited" if VALIDATION_MARK in reason else "judged"
    if code == "vlm_error":
        return "edited" if reason_code(reason[len(code) + 1:]) == "judge" else "proposed"
    if row.get("mining_status") == "refused" and row.get("command_json") and code not in UNGROUNDED_REFUSALS:
        return "grounded"
    return "proposed"


def failure_classes(reason: str) -> tuple[str, ...]:
    """The classes of one ``failure_reason`` for ranking (``()`` for none): the refusal reason
    (``"no_asset"``), ``"vlm_error: <stage>"``, ``"error"`` (storing failed), or for a rejection one class per
    validation failure kind (``"rejected: collision"``, ``"rejected: offroad"``, ``"rejected: kinematic"``) and the
    judge's (``"rejected: does not follow the prompt"``, ``"rejected: implausible"``)."""
    code = reason_code(reason)
    if not code:
        return ()
    if code == "vlm_error":
        return (f"vlm_error: {reason_code(reason[len(code) + 1:])}",)
    if code != "rejected":
        return (code,)
    validation, _, judge = reason.partition(" | judge: ") if VALIDATION_MARK in reason else ("", "", reason)
    found = [f"rejected: {kind}" for phrase, kind in VALIDATION_PHRASES.items() if phrase in validation]
    if "does not follow the prompt" in judge:
        found.append("rejected: does not follow the prompt")
    scores = _PLAUSIBILITY.search(judge)
    if scores is not None and int(scores.group(1)) < int(scores.group(2)):
        found.append("rejected: implausible")
    return tuple(found) or ("rejected",)


@dataclass(frozen=True)
class FunnelRow:
    """The funnel of one edit category (or ``"total"``).

    Attributes:
        category: the edit category (``eval.mining.UNKNOWN_CATEGORY`` when none is known; ``"total"``: all).
        proposals: ``[len(FUNNEL_STAGES)]`` proposals whose furthest attempt passed each stage.
        attempts: ``[len(FUNNEL_STAGES)]`` attempts that passed each stage.
    """

    category: str
    proposals: tuple[int, ...]
    attempts: tuple[int, ...]


def _passed(stages: Iterable[int]) -> tuple[int, ...]:
    """Counts per stage of items whose furthest stage index is each of ``stages`` -> items passing each stage."""
    reached = Counter(stages)
    return tuple(sum(n for k, n in reached.items() if k >= s) for s in range(len(FUNNEL_STAGES)))


def _category(rows: Sequence[Mapping[str, Any]]) -> str:
    return next((str(r["category"]) for r in reversed(rows) if r.get("category")), UNKNOWN_CATEGORY)


def funnel_rows(rows: Iterable[Mapping[str, Any]]) -> list[FunnelRow]:
    """The funnel per edit category (``EDIT_CATEGORIES`` present, then others seen, then ``"total"``) of a mining
    run's edits-table rows; a proposal's category is the one ``eval.mining.proposal_outcomes`` gives it.

    Raises:
        ValueError: a row without the mining columns (naming its ``edit_id``).
    """
    proposals: list[Sequence[Mapping[str, Any]]] = list(group_proposals(rows).values())
    by_category: dict[str, list[Sequence[Mapping[str, Any]]]] = {}
    for attempts in proposals:
        by_category.setdefault(_category(attempts), []).append(attempts)
    order = [c for c in EDIT_CATEGORIES if c in by_category] + sorted(set(by_category) - set(EDIT_CATEGORIES))
    groups: list[tuple[str, list[Sequence[Mapping[str, Any]]]]] = [(c, by_category[c]) for c in order]
    out = []
    for category, chosen in [*groups, ("total", proposals)]:
        stages = [[FUNNEL_STAGES.index(stage_reached(r)) for r in attempts] for attempts in chosen]
        out.append(FunnelRow(category, _passed(max(s) for s in stages), _passed(k for s in stages for k in s)))
    return out


__all__ = ["FUNNEL_STAGES", "UNGROUNDED_REFUSALS", "VALIDATION_MARK", "VALIDATION_PHRASES", "FunnelRow",
           "failure_classes", "funnel_rows", "reason_code", "stage_reached"]
