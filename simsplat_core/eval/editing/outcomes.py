"""One method's result on one prompt, and the tables that sum them up (SIMSplat Table 3, edit fidelity).

Tables (pyarrow; each declared here as a ``TableSpec``: schema, column meanings, Markdown):

* ``editing``: one row per (method, category) -- the six categories and ``total`` -- with ``prompts``,
  ``completed`` and ``rate``;
* ``editing_infeasible``: per method, how many of the infeasible prompts it refused (and with a reason
  that names the problem);
* ``edit_fidelity``: per (method, category), the mean fidelity of completed edits that the world could
  re-render natively (``fidelity.py``), next to the unedited scene's test PSNR;
* ``editing_outcomes``: every (method, prompt) with the check's reason, so failures can be read.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa

from simsplat_core.eval.editing.fidelity import FidelityScore
from simsplat_core.eval.editing.prompts import CATEGORIES, INFEASIBLE, EditPrompt
from simsplat_core.eval.table_headlines import PAPER, Headline, PaperFigure
from simsplat_core.eval.table_spec import Column, TableSpec, markdown

#: Methods of the tables, in row order.
METHOD_NAMES: tuple[str, ...] = ("ours", "chatsim-like", "omnire-like")

_METHOD = Column("method", pa.string(), f"the editing method ({' / '.join(METHOD_NAMES)})")
_CATEGORY = Column("category", pa.string(), "the prompt category (the six edit categories, or total)")
_TOTAL = (("category", "total"),)

#: ``tables/editing``: task completion per (method, category) (Table 3).
EDITING_SPEC = TableSpec("editing", "Editing: task completion", "(method, category)", (
    _METHOD, _CATEGORY,
    Column("prompts", pa.int64(), "feasible prompts of the category", "count"),
    Column("completed", pa.int64(), "prompts whose edit passed the ground-truth check", "count"),
    Column("rate", pa.float64(), "completed / prompts (NaN without prompts)", "share"),
), keys=("method", "category"), headlines=(Headline("rate", where=_TOTAL),), paper=(
    PaperFigure("rate", 0.842, (("method", "ours"), ("category", "total")), PAPER,
                "Waymo scenes with the paper's own prompt set: for orientation, not like-for-like"),))
#: ``tables/editing_infeasible``: infeasible prompts refused per method.
INFEASIBLE_SPEC = TableSpec("editing_infeasible", "Editing: infeasible prompts refused", "method", (
    _METHOD,
    Column("prompts", pa.int64(), "infeasible prompts", "count"),
    Column("refused", pa.int64(), "infeasible prompts the method refused", "count"),
    Column("rate", pa.float64(), "refused / prompts (NaN without prompts)", "share"),
    Column("expected_reason", pa.int64(), "refusals whose reason names the prompt's problem", "count"),
), keys=("method",), headlines=(Headline("rate"),))
#: ``tables/edit_fidelity``: mean fidelity of the completed, natively re-rendered edits.
FIDELITY_SPEC = TableSpec("edit_fidelity", "Edit fidelity vs the world's rendering of the edit", "(method, category)", (
    _METHOD, _CATEGORY,
    Column("edits", pa.int64(), "completed edits the world re-rendered natively", "count"),
    Column("psnr", pa.float64(), "mean PSNR of the edited render vs the world's render of the edit", "dB"),
    Column("ssim", pa.float64(), "mean SSIM of the same", ""),
    Column("psnr_unedited", pa.float64(), "mean test PSNR of the unedited scenes of these edits", "dB"),
    Column("psnr_region", pa.float64(), "mean PSNR inside the edited region", "dB"),
    Column("psnr_unedited_region", pa.float64(), "mean PSNR of the unedited render inside the same region", "dB"),
), keys=("method", "category"), digits=2, headlines=(Headline("psnr", where=_TOTAL),))


def _failed(table: pa.Table) -> list[int]:
    return [k for k, done in enumerate(table["completed"].to_pylist()) if not done]


#: ``tables/editing_outcomes``: every (method, prompt) with the check's reason (Markdown: the failed ones).
OUTCOMES_SPEC = TableSpec("editing_outcomes", "Editing: every prompt", "(method, prompt)", (
    _METHOD,
    Column("seq_id", pa.string(), "the edited sequence"),
    Column("prompt_id", pa.string(), "the prompt's id in the prompt set"),
    _CATEGORY,
    Column("kind", pa.string(), "the prompt's kind within its category"),
    Column("text", pa.string(), "the prompt"),
    Column("completed", pa.bool_(), "the check passed (infeasible prompts: the edit was refused)"),
    Column("refusal", pa.string(), "the editor's refusal reason (\"\": not refused)"),
    Column("reason", pa.string(), "the check's reason: what was measured or what failed"),
    Column("validation", pa.string(), "the editor's own validation: ok | failed | \"\" (refused)"),
    Column("seconds", pa.float64(), "edit wall time: parse, ground, apply, validate", "s"),
    Column("psnr", pa.float64(), "fidelity PSNR of a completed, natively re-rendered edit (else NaN)", "dB"),
    Column("psnr_region", pa.float64(), "the same inside the edited region", "dB"),
), keys=("method", "seq_id", "prompt_id"), printed=("method", "category", "text", "refusal", "reason"),
    row_filter=_failed, detail=True)

#: The editing evaluation's tables, in the order they are written.
EDITING_SPECS: tuple[TableSpec, ...] = (EDITING_SPEC, INFEASIBLE_SPEC, FIDELITY_SPEC, OUTCOMES_SPEC)


@dataclass(frozen=True)
class PromptOutcome:
    """One method on one prompt.

    Attributes:
        prompt: the prompt.
        method: the method's name.
        completed: the check passed (infeasible prompts: the edit was refused).
        reason: the check's reason (what was measured, or what failed).
        refusal: the ``EditRefused.reason`` when the method refused, else ``""``.
        seconds: edit wall time (parse + ground + apply + validate); check_seconds: renders and checks.
        validation: the editor's own validation, ``"ok"`` / ``"failed"`` / ``""`` (refused).
        fidelity: fidelity of a completed edit the world re-rendered natively, else ``None``.
        measured: the check's measurements.
    """

    prompt: EditPrompt
    method: str
    completed: bool
    reason: str
    refusal: str = ""
    seconds: float = 0.0
    check_seconds: float = 0.0
    validation: str = ""
    fidelity: FidelityScore | None = None
    measured: dict[str, float] = field(default_factory=dict)


def _methods(outcomes: Sequence[PromptOutcome]) -> list[str]:
    present = dict.fromkeys(o.method for o in outcomes)
    return [m for m in METHOD_NAMES if m in present] + [m for m in present if m not in METHOD_NAMES]


def completion_table(outcomes: Sequence[PromptOutcome]) -> pa.Table:
    """``editing``: prompts / completed / rate per (method, category) and ``total`` (feasible prompts only)."""
    rows = []
    for method in _methods(outcomes):
        mine = [o for o in outcomes if o.method == method and o.prompt.category != INFEASIBLE]
        for category in (*CATEGORIES, "total"):
            cat = mine if category == "total" else [o for o in mine if o.prompt.category == category]
            done = sum(o.completed for o in cat)
            rows.append({"method": method, "category": category, "prompts": len(cat), "completed": done,
                         "rate": done / len(cat) if cat else math.nan})
    return EDITING_SPEC.table(rows)


def infeasible_table(outcomes: Sequence[PromptOutcome]) -> pa.Table:
    """``editing_infeasible``: refused infeasible prompts per method."""
    rows = []
    for method in _methods(outcomes):
        mine = [o for o in outcomes if o.method == method and o.prompt.category == INFEASIBLE]
        refused = sum(o.completed for o in mine)
        expected = sum(o.completed and o.refusal in o.prompt.intent.expected_refusals for o in mine)
        rows.append({"method": method, "prompts": len(mine), "refused": refused,
                     "rate": refused / len(mine) if mine else math.nan, "expected_reason": expected})
    return INFEASIBLE_SPEC.table(rows)


def _mean(values: list[float]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else math.nan


def fidelity_table(outcomes: Sequence[PromptOutcome], unedited_psnr: Mapping[str, float]) -> pa.Table:
    """``edit_fidelity``: mean fidelity of completed, natively re-rendered edits per (method, category).

    ``unedited_psnr`` is each scene's test PSNR (the unedited render against the log's test images);
    ``psnr_unedited`` averages it over the scenes of the measured edits.
    """
    rows = []
    for method in _methods(outcomes):
        mine = [o for o in outcomes if o.method == method and o.fidelity is not None and o.completed
                and o.prompt.category != INFEASIBLE]
        for category in (*CATEGORIES, "total"):
            cat = mine if category == "total" else [o for o in mine if o.prompt.category == category]
            scores = [o.fidelity for o in cat if o.fidelity is not None]
            rows.append({"method": method, "category": category, "edits": len(scores),
                         "psnr": _mean([s.psnr for s in scores]), "ssim": _mean([s.ssim for s in scores]),
                         "psnr_unedited": _mean([unedited_psnr.get(o.prompt.seq_id, math.nan) for o in cat]),
                         "psnr_region": _mean([s.psnr_region for s in scores]),
                         "psnr_unedited_region": _mean([s.psnr_unedited_region for s in scores])})
    return FIDELITY_SPEC.table(rows)


def outcomes_table(outcomes: Sequence[PromptOutcome]) -> pa.Table:
    """``editing_outcomes``: every (method, prompt)."""
    rows = [{"method": o.method, "seq_id": o.prompt.seq_id, "prompt_id": o.prompt.prompt_id,
             "category": o.prompt.category, "kind": o.prompt.kind, "text": o.prompt.text, "completed": o.completed,
             "refusal": o.refusal, "reason": o.reason, "validation": o.validation, "seconds": float(o.seconds),
             "psnr": o.fidelity.psnr if o.fidelity is not None else math.nan,
             "psnr_region": o.fidelity.psnr_region if o.fidelity is not None else math.nan} for o in outcomes]
    return OUTCOMES_SPEC.table(rows)


def failures_markdown(outcomes: Sequence[PromptOutcome], method: str = "ours") -> str:
    """The failed prompts of ``method`` as Markdown: category, text, reason."""
    table = outcomes_table([o for o in outcomes if o.method == method and not o.completed])
    return markdown(table, columns=("category", "kind", "text", "refusal", "reason"))


__all__ = ["EDITING_SPEC", "EDITING_SPECS", "FIDELITY_SPEC", "INFEASIBLE_SPEC", "METHOD_NAMES", "OUTCOMES_SPEC",
           "PromptOutcome", "completion_table", "failures_markdown", "fidelity_table",
           "infeasible_table", "outcomes_table"]
