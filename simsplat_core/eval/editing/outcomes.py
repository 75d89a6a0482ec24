"""One method's result on one prompt, and the tables that sum them up (SIMSplat Table 3, edit fidelity).

Tables (pyarrow, schemas in ``storage.schemas``; Markdown via ``eval.tables.markdown``):

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
from simsplat_core.eval.tables import markdown

#: Methods of the tables, in row order.
METHOD_NAMES: tuple[str, ...] = ("ours", "chatsim-like", "omnire-like")
#: Columns of each table (``storage.schemas.editing_table_schema`` adds the file metadata).
TABLE_COLUMNS: dict[str, tuple[tuple[str, pa.DataType], ...]] = {
    "editing": (("method", pa.string()), ("category", pa.string()), ("prompts", pa.int64()),
                ("completed", pa.int64()), ("rate", pa.float64())),
    "editing_infeasible": (("method", pa.string()), ("prompts", pa.int64()), ("refused", pa.int64()),
                           ("rate", pa.float64()), ("expected_reason", pa.int64())),
    "edit_fidelity": (("method", pa.string()), ("category", pa.string()), ("edits", pa.int64()),
                      ("psnr", pa.float64()), ("ssim", pa.float64()), ("psnr_unedited", pa.float64()),
                      ("psnr_region", pa.float64()), ("psnr_unedited_region", pa.float64())),
    "editing_outcomes": (("method", pa.string()), ("seq_id", pa.string()), ("prompt_id", pa.string()),
                         ("category", pa.string()), ("kind", pa.string()), ("text", pa.string()),
                         ("completed", pa.bool_()), ("refusal", pa.string()), ("reason", pa.string()),
                         ("validation", pa.string()), ("seconds", pa.float64()), ("psnr", pa.float64()),
                         ("psnr_region", pa.float64())),
}


def _table(name: str, rows: list[dict]) -> pa.Table:
    schema = pa.schema([pa.field(n, t, nullable=False) for n, t in TABLE_COLUMNS[name]])
    return pa.Table.from_pylist(rows, schema=schema)


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
    return _table("editing", rows)


def infeasible_table(outcomes: Sequence[PromptOutcome]) -> pa.Table:
    """``editing_infeasible``: refused infeasible prompts per method."""
    rows = []
    for method in _methods(outcomes):
        mine = [o for o in outcomes if o.method == method and o.prompt.category == INFEASIBLE]
        refused = sum(o.completed for o in mine)
        expected = sum(o.completed and o.refusal in o.prompt.intent.expected_refusals for o in mine)
        rows.append({"method": method, "prompts": len(mine), "refused": refused,
                     "rate": refused / len(mine) if mine else math.nan, "expected_reason": expected})
    return _table("editing_infeasible", rows)


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
    return _table("edit_fidelity", rows)


def outcomes_table(outcomes: Sequence[PromptOutcome]) -> pa.Table:
    """``editing_outcomes``: every (method, prompt)."""
    rows = [{"method": o.method, "seq_id": o.prompt.seq_id, "prompt_id": o.prompt.prompt_id,
             "category": o.prompt.category, "kind": o.prompt.kind, "text": o.prompt.text, "completed": o.completed,
             "refusal": o.refusal, "reason": o.reason, "validation": o.validation, "seconds": float(o.seconds),
             "psnr": o.fidelity.psnr if o.fidelity is not None else math.nan,
             "psnr_region": o.fidelity.psnr_region if o.fidelity is not None else math.nan} for o in outcomes]
    return _table("editing_outcomes", rows)


def failures_markdown(outcomes: Sequence[PromptOutcome], method: str = "ours") -> str:
    """The failed prompts of ``method`` as Markdown: category, text, reason."""
    table = outcomes_table([o for o in outcomes if o.method == method and not o.completed])
    return markdown(table, columns=("category", "kind", "text", "refusal", "reason"))


__all__ = ["METHOD_NAMES", "PromptOutcome", "completion_table", "failures_markdown", "fidelity_table",
           "infeasible_table", "outcomes_table"]
