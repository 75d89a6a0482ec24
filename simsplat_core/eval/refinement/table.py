"""The ``motion`` table (DESIGN.md): one row per (dataset, method, predictor); and the per-case outcomes table.

Columns (:data:`MOTION_COLUMNS`, declared with their meanings as :data:`MOTION_SPEC`):
``dataset`` (``"synthetic"``, a real dataset such as ``"waymo-motion"`` / ``"av2"``, or ``"<dataset>+edits"``
for scripted edits of real scenarios), ``method`` (``"log"``, ``"none"``, ``"single-agent"``, ``"full"``),
``predictor`` (the motion predictor's name, ``""`` for the ``log`` and ``none`` rows), ``scenarios``,
``refused`` (cases the editor refused, left out of every mode's rates; 0 for real rollouts); failure rates
over scenarios in ``[0, 1]`` (``collision_vehicle``, ``collision_pedestrian``, ``offroad``, ``kinematic``,
``failure``: a scenario fails when any agent fails); ``progress`` and ``stopped_share`` (NaN where no agent
moved); ``ade_3s`` / ``ade_8s`` (null for the log row, for edits and where the data ends before the horizon);
``agent_collision`` / ``agent_offroad``, the share of agents that collide / leave the road (informative where
there are few scenarios).

The outcomes table (:data:`OUTCOME_COLUMNS`, :data:`OUTCOMES_SPEC`, ``motion_outcomes.parquet``) has one row per
(edit case, mode), with the failing agents and what happened to each, so failures can be inspected.

    rows = motion_rows(synthetic_rows(...), real_rows(...).rows, evaluate_real_edits(...).rows)
    table = motion_table(rows); text = MOTION_SPEC.render_markdown(table)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import pyarrow as pa

from simsplat_core.eval.table_headlines import PAPER, Headline, PaperFigure
from simsplat_core.eval.table_spec import Column, TableSpec

#: ``(name, type, nullable)`` of the ``motion`` table's columns, in order.
MOTION_COLUMNS: tuple[tuple[str, pa.DataType, bool], ...] = (
    ("dataset", pa.string(), False),
    ("method", pa.string(), False),
    ("predictor", pa.string(), False),
    ("scenarios", pa.int64(), False),
    ("refused", pa.int64(), False),
    ("collision_vehicle", pa.float64(), False),
    ("collision_pedestrian", pa.float64(), False),
    ("offroad", pa.float64(), False),
    ("kinematic", pa.float64(), False),
    ("failure", pa.float64(), False),
    ("progress", pa.float64(), False),
    ("stopped_share", pa.float64(), False),
    ("ade_3s", pa.float64(), True),
    ("ade_8s", pa.float64(), True),
    ("agent_collision", pa.float64(), False),
    ("agent_offroad", pa.float64(), False),
)
#: Columns that are shares in ``[0, 1]``.
RATE_COLUMNS: tuple[str, ...] = ("collision_vehicle", "collision_pedestrian", "offroad", "kinematic", "failure",
                                 "agent_collision", "agent_offroad")

_MOTION_MEANINGS: dict[str, tuple[str, str]] = {
    "dataset": ("synthetic, a real dataset (waymo-motion, av2) or <dataset>+edits", ""),
    "method": ("log | none | single-agent | full", ""),
    "predictor": ("the motion predictor (\"\" for the log and none rows)", ""),
    "scenarios": ("scenarios evaluated", "count"),
    "refused": ("cases the editor refused, left out of the rates", "count"),
    "collision_vehicle": ("scenarios where an agent collides with a vehicle", "share"),
    "collision_pedestrian": ("scenarios where an agent collides with a pedestrian", "share"),
    "offroad": ("scenarios where an agent leaves the road", "share"),
    "kinematic": ("scenarios where an agent breaks the kinematic limits", "share"),
    "failure": ("scenarios where any agent fails", "share"),
    "progress": ("mean progress along the agents' log paths (NaN where no agent moved)", "share"),
    "stopped_share": ("share of moving agents that stop", "share"),
    "ade_3s": ("average displacement error over 3 s (null: undefined)", "m"),
    "ade_8s": ("average displacement error over 8 s (null: undefined)", "m"),
    "agent_collision": ("agents that collide", "share"),
    "agent_offroad": ("agents that leave the road", "share"),
}
#: The rows of the full refinement (every agent reacts), whose figures the trends follow.
_FULL = (("method", "full"),)
#: ``tables/motion``: one row per (dataset, method, predictor).
MOTION_SPEC = TableSpec(
    "motion", "Motion: failure rates, progress, ADE", "(dataset, method, predictor)",
    tuple(Column(n, t, *_MOTION_MEANINGS[n], nullable=nl) for n, t, nl in MOTION_COLUMNS),
    keys=("dataset", "method", "predictor"), version=2,  # 2: predictor and refused columns
    headlines=(Headline("failure", where=_FULL, better="lower"), Headline("progress", where=_FULL)),
    paper=tuple(PaperFigure(column, value, (("dataset", "synthetic"), *_FULL), PAPER,
                            "the paper's collision rate after its refinement, on Waymo scenes with its own edits")
                for column, value in (("collision_vehicle", 0.085), ("collision_pedestrian", 0.033))))


def motion_rows(*groups: Sequence[Mapping[str, Any]]) -> list[dict]:
    """The table's rows: every group's, in order (``simsplat eval motion``: synthetic, real, real edits)."""
    return [dict(r) for group in groups for r in group]


def motion_table(rows: Sequence[Mapping[str, Any]]) -> pa.Table:
    """Rows -> a pyarrow table of :data:`MOTION_COLUMNS` (``None`` floats of non-nullable columns -> NaN).

    Raises:
        KeyError: a row lacks a column (named).
        ValueError: a rate outside ``[0, 1]`` (named with its row).
    """
    data: dict[str, list] = {}
    for name, _, nullable in MOTION_COLUMNS:
        values = []
        for k, row in enumerate(rows):
            if name not in row:
                raise KeyError(f"motion row {k} ({row.get('dataset')}, {row.get('method')}) has no column {name!r}")
            value = row[name]
            if value is None and not nullable and name not in ("dataset", "method", "predictor", "scenarios",
                                                               "refused"):
                value = math.nan
            if name in RATE_COLUMNS and value is not None and not math.isnan(value) and not 0.0 <= value <= 1.0:
                raise ValueError(f"motion row {k} ({row['dataset']}, {row['method']}): {name} = {value} "
                                 "is not in [0, 1]")
            values.append(value)
        data[name] = values
    return pa.Table.from_pydict(data, schema=MOTION_SPEC.schema)


#: ``(name, type, nullable)`` of the outcomes table's columns (one row per edit case and refinement mode).
OUTCOME_COLUMNS: tuple[tuple[str, pa.DataType, bool], ...] = (
    ("case_id", pa.string(), False),
    ("dataset", pa.string(), False),
    ("seq_id", pa.string(), False),
    ("source", pa.string(), False),  # "editing", "interaction" or "real-edit"
    ("kind", pa.string(), False),  # the editing category, the interaction kind or the real edit's name
    ("text", pa.string(), False),
    ("mode", pa.string(), False),
    ("predictor", pa.string(), False),
    ("refused", pa.string(), False),  # the refusal ("" when carried out)
    ("collision_vehicle", pa.bool_(), False),
    ("collision_pedestrian", pa.bool_(), False),
    ("collision_static", pa.bool_(), False),
    ("offroad", pa.bool_(), False),
    ("kinematic", pa.bool_(), False),
    ("failure", pa.bool_(), False),
    ("failed_agents", pa.string(), False),  # comma separated ids
    ("failure_details", pa.string(), False),  # one "<id> [<source> <category>]: what" per failed agent, " | "
    ("refined", pa.int64(), False),  # agents that reacted
    ("progress", pa.float64(), False),
    ("stopped_share", pa.float64(), False),
    ("seconds", pa.float64(), False),
)

_OUTCOME_MEANINGS: dict[str, tuple[str, str]] = {
    "case_id": ("the edit case", ""), "dataset": ("the case's dataset", ""), "seq_id": ("the sequence", ""),
    "source": ("editing | interaction | real-edit", ""),
    "kind": ("the editing category, the interaction kind or the real edit's name", ""),
    "text": ("the prompt", ""), "mode": ("the refinement mode: none | single-agent | full", ""),
    "predictor": ("the motion predictor", ""), "refused": ("the editor's refusal (\"\": carried out)", ""),
    "collision_vehicle": ("an agent collides with a vehicle", ""),
    "collision_pedestrian": ("an agent collides with a pedestrian", ""),
    "collision_static": ("an agent collides with a static object", ""),
    "offroad": ("an agent leaves the road", ""), "kinematic": ("an agent breaks the kinematic limits", ""),
    "failure": ("any agent fails", ""), "failed_agents": ("the failed agents' ids, comma separated", ""),
    "failure_details": ("per failed agent: <id> [<source> <category>]: what happened, ' | ' separated", ""),
    "refined": ("agents that reacted", "count"), "progress": ("mean progress along the log paths", "share"),
    "stopped_share": ("share of moving agents that stop", "share"), "seconds": ("wall time of the case", "s"),
}


def _failed_or_refused(table: pa.Table) -> list[int]:
    return [k for k, (f, r) in enumerate(zip(table["failure"].to_pylist(), table["refused"].to_pylist())) if f or r]


#: ``tables/motion_outcomes``: one row per (edit case, mode); its Markdown lists the failed or refused ones.
OUTCOMES_SPEC = TableSpec(
    "motion_outcomes", "Motion: every edit case and mode", "(edit case, refinement mode)",
    tuple(Column(n, t, *_OUTCOME_MEANINGS[n], nullable=nl) for n, t, nl in OUTCOME_COLUMNS),
    keys=("case_id", "mode"), printed=("dataset", "seq_id", "kind", "mode", "text", "refused", "failure_details"),
    row_filter=_failed_or_refused, detail=True)


def outcomes_table(rows: Sequence[Mapping[str, Any]]) -> pa.Table:
    """Outcome rows -> a pyarrow table of :data:`OUTCOME_COLUMNS` (``KeyError`` naming a missing column)."""
    data: dict[str, list] = {}
    for name, _, _ in OUTCOME_COLUMNS:
        values = []
        for k, row in enumerate(rows):
            if name not in row:
                raise KeyError(f"outcome row {k} ({row.get('case_id')}) has no column {name!r}")
            values.append(row[name])
        data[name] = values
    return pa.Table.from_pydict(data, schema=OUTCOMES_SPEC.schema)


__all__ = ["MOTION_COLUMNS", "MOTION_SPEC", "OUTCOMES_SPEC", "OUTCOME_COLUMNS", "RATE_COLUMNS", "motion_rows",
           "motion_table", "outcomes_table"]
