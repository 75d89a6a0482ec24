"""Evaluation tables as pyarrow Tables and Markdown (no pandas).

Grounding (SIMSplat Table 2 / Table 3 layout): one row per method (or per feature ablation), columns
``vehicle_acc, vehicle_viou, pedestrian_acc, pedestrian_viou, total_acc, total_viou`` and the query
counts. ``grounding_table`` takes the summary of ``eval.grounding.metrics.summarise`` and the row order with
display names; ``ablation_table`` is the same with the first column named ``features`` (rows App /
App+Mot / App+Loc / All). ``markdown`` renders any flat table.

    table = grounding_table(results.summary(), {"LangSplat-like": "app", "4D-LangSplat-like": "frames", "Ours": "all"})
    print(markdown(table))
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import pyarrow as pa

from simsplat_core.eval.grounding.metrics import CATEGORIES, CategoryScore

#: The metric columns of a grounding table, in order.
GROUNDING_COLUMNS: tuple[str, ...] = tuple(f"{c}_{m}" for c in CATEGORIES for m in ("acc", "viou"))
#: The rows of the feature ablation (SIMSplat Table 3).
ABLATION_ROWS: tuple[str, ...] = ("App", "App+Mot", "App+Loc", "All")


def grounding_table(
    summary: Mapping[str, Mapping[str, CategoryScore]],
    rows: Mapping[str, str],
    first_column: str = "method",
) -> pa.Table:
    """One row per entry of ``rows`` (display name -> method key of ``summary``), in that order.

    Columns: ``first_column`` (string), the ``GROUNDING_COLUMNS`` (float64), ``vehicle_queries``,
    ``pedestrian_queries``, ``total_queries`` (int64).

    Raises:
        KeyError: a row names a method that ``summary`` lacks.
    """
    missing = [key for key in rows.values() if key not in summary]
    if missing:
        raise KeyError(f"no results for methods {missing}; have {sorted(summary)}")
    data: dict[str, list] = {first_column: list(rows)}
    for col in GROUNDING_COLUMNS:
        cat, metric = col.rsplit("_", 1)
        data[col] = [
            float(getattr(summary[key][cat], "accuracy" if metric == "acc" else "viou")) for key in rows.values()
        ]
    for cat in CATEGORIES:
        data[f"{cat}_queries"] = [int(summary[key][cat].queries) for key in rows.values()]
    schema = pa.schema(
        [pa.field(first_column, pa.string())]
        + [pa.field(c, pa.float64()) for c in GROUNDING_COLUMNS]
        + [pa.field(f"{c}_queries", pa.int64()) for c in CATEGORIES]
    )
    return pa.Table.from_pydict(data, schema=schema)


def ablation_table(summary: Mapping[str, Mapping[str, CategoryScore]], rows: Mapping[str, str]) -> pa.Table:
    """``grounding_table`` with a ``features`` first column; ``rows`` maps ``ABLATION_ROWS`` names to methods."""
    unknown = [r for r in rows if r not in ABLATION_ROWS]
    if unknown:
        raise ValueError(f"ablation rows must be among {ABLATION_ROWS}, got {unknown}")
    return grounding_table(summary, rows, first_column="features")


def _cell(value, digits: int) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "–" if math.isnan(value) else f"{value:.{digits}f}"
    return str(value).replace("|", "\\|")


def markdown(table: pa.Table, digits: int = 3, columns: tuple[str, ...] | None = None) -> str:
    """A GitHub Markdown table of ``table`` (floats with ``digits`` decimals, NaN as ``–``)."""
    names = list(columns) if columns is not None else table.column_names
    missing = [c for c in names if c not in table.column_names]
    if missing:
        raise KeyError(f"table has no columns {missing}; it has {table.column_names}")
    rows = table.select(names).to_pylist()
    header = "| " + " | ".join(names) + " |"
    align = "|" + "|".join(":---" if i == 0 else "---:" for i in range(len(names))) + "|"
    body = ["| " + " | ".join(_cell(r[c], digits) for c in names) + " |" for r in rows]
    return "\n".join([header, align, *body]) + "\n"


def grounding_markdown(table: pa.Table, digits: int = 3) -> str:
    """The paper's layout: first column, then Acc / vIoU for vehicles, pedestrians and total."""
    return markdown(table, digits, (table.column_names[0], *GROUNDING_COLUMNS))


__all__ = ["ABLATION_ROWS", "GROUNDING_COLUMNS", "ablation_table", "grounding_markdown", "grounding_table", "markdown"]
