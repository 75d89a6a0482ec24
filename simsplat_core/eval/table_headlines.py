"""Headline metrics and the paper's reference figures of a declared evaluation table.

A table declares (``TableSpec.headlines``) which of its columns summarise it across runs, and for which rows:

    Headline("rate", where=(("category", "total"),))          # one series per method: the total rate
    Headline("failure", better="lower")                        # one series per row key (dataset, method, ...)
    Headline("timestamp_ba", reduce="mean")                    # one series: the mean over every row

and which of its cells the paper reports (``TableSpec.paper``), on which rows:

    PaperFigure("rate", 0.842, where=(("method", "ours"), ("category", "total")), source="SIMSplat paper")

``headline_values(headline, table, keys)`` gives a table's ``(series label, value)`` pairs; dashboards and
summaries draw trends from them. Framework-free (pyarrow and math only).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import pyarrow as pa

#: How a headline reduces the rows it selects: ``"each"`` (one series per row) or ``"mean"`` (their NaN-free mean).
REDUCTIONS: tuple[str, ...] = ("each", "mean")
#: Which way a headline improves.
BETTER: tuple[str, ...] = ("higher", "lower")
#: The label of the one series of a ``"mean"`` headline.
MEAN_LABEL = "mean"
#: The source of the paper's figures.
PAPER = "SIMSplat paper (arXiv 2510.02469), Waymo scenes"

Where = tuple[tuple[str, str], ...]


def _matches(row: dict[str, Any], where: Where) -> bool:
    return all(str(row.get(column)) == value for column, value in where)


@dataclass(frozen=True)
class Headline:
    """A metric that summarises a table across runs.

    Attributes:
        column: the metric column.
        where: ``(column, value)`` pairs a row must match (values compared as strings); ``()``: every row.
        reduce: ``"each"``: one series per selected row, labelled by its key values not fixed by ``where``;
            ``"mean"``: one series, the mean of the selected rows' finite values.
        better: ``"higher"`` or ``"lower"``.
    """

    column: str
    where: Where = ()
    reduce: str = "each"
    better: str = "higher"

    def __post_init__(self) -> None:
        if self.reduce not in REDUCTIONS:
            raise ValueError(f"Headline {self.column!r}: reduce must be one of {list(REDUCTIONS)}, got {self.reduce!r}")
        if self.better not in BETTER:
            raise ValueError(f"Headline {self.column!r}: better must be one of {list(BETTER)}, got {self.better!r}")

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column the headline names."""
        return (self.column, *(c for c, _ in self.where))


@dataclass(frozen=True)
class PaperFigure:
    """One figure the paper reports for a cell of a table.

    Attributes:
        column: the column it corresponds to.
        value: the paper's figure (in the column's unit).
        where: ``(column, value)`` pairs naming the row it corresponds to (values compared as strings).
        source: where the paper reports it ("SIMSplat paper, Waymo scenes").
        note: how it compares (a different prompt set, another measure of the same thing), or ``""``.
    """

    column: str
    value: float
    where: Where
    source: str
    note: str = ""

    @property
    def columns(self) -> tuple[str, ...]:
        return (self.column, *(c for c, _ in self.where))

    def matching_value(self, table: pa.Table) -> float | None:
        """Our value of the cell: the column's value on the first row matching :attr:`where` (``None``: no row)."""
        for row in table.select(list(dict.fromkeys(self.columns))).to_pylist():
            if _matches(row, self.where):
                value = row[self.column]
                return None if value is None else float(value)
        return None


def _finite(value: Any) -> float | None:
    if value is None or isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def headline_values(headline: Headline, table: pa.Table, keys: Sequence[str]) -> list[tuple[str, float]]:
    """``(series label, value)`` of ``headline`` in ``table`` (a table of the declaration whose row keys are
    ``keys``): one pair per selected row with a finite value (``"each"``), or one ``("mean", mean)`` pair when any
    selected row has one (``"mean"``). Non-finite and null values are left out."""
    fixed = {c for c, _ in headline.where}
    label_keys = [k for k in keys if k not in fixed and k != headline.column]
    rows = [r for r in table.select(list(dict.fromkeys((*headline.columns, *label_keys)))).to_pylist()
            if _matches(r, headline.where)]
    values = [(" / ".join(str(r[k]) for k in label_keys) or headline.column, _finite(r[headline.column]))
              for r in rows]
    kept = [(label, v) for label, v in values if v is not None]
    if headline.reduce == "mean":
        return [(MEAN_LABEL, sum(v for _, v in kept) / len(kept))] if kept else []
    return kept


__all__ = ["BETTER", "Headline", "MEAN_LABEL", "PAPER", "PaperFigure", "REDUCTIONS", "Where", "headline_values"]
