"""The grounding evaluation's tables (SIMSplat Table 2 / Table 3 layout) and their declarations.

* ``grounding`` (:data:`GROUNDING_SPEC`): one row per method, columns ``vehicle_acc, vehicle_viou,
  pedestrian_acc, pedestrian_viou, total_acc, total_viou`` and the query counts;
* ``grounding_ablation`` (:data:`ABLATION_SPEC`): the same with the first column ``features`` (rows App /
  App+Mot / App+Loc / All);
* ``grounding_outcomes`` (:data:`OUTCOMES_SPEC`): every method's answer to every query.

``grounding_table`` takes the summary of ``eval.grounding.metrics.summarise`` and the row order with display
names:

    table = grounding_table(results.summary(), {"LangSplat-like": "app", "4D-LangSplat-like": "frames", "Ours": "all"})
    print(GROUNDING_SPEC.render_markdown(table))
"""

from __future__ import annotations

from collections.abc import Mapping

import pyarrow as pa

from simsplat_core.eval.grounding.metrics import CATEGORIES, CategoryScore, GroundingResults
from simsplat_core.eval.table_headlines import Headline
from simsplat_core.eval.table_spec import Column, TableSpec

#: The metric columns of a grounding table, in order.
GROUNDING_COLUMNS: tuple[str, ...] = tuple(f"{c}_{m}" for c in CATEGORIES for m in ("acc", "viou"))
#: The rows of the feature ablation (SIMSplat Table 3).
ABLATION_ROWS: tuple[str, ...] = ("App", "App+Mot", "App+Loc", "All")


def _score_columns(first_column: str, first_meaning: str) -> tuple[Column, ...]:
    metric = {"acc": ("accuracy: share of queries answered with exactly the target nodes", "share"),
              "viou": ("mean video IoU of the predicted masks with the targets' masks", "share")}
    return (Column(first_column, pa.string(), first_meaning),
            *(Column(f"{c}_{m}", pa.float64(), f"{metric[m][0]} ({c} queries)", metric[m][1])
              for c in CATEGORIES for m in ("acc", "viou")),
            *(Column(f"{c}_queries", pa.int64(), f"{c} queries asked", "count") for c in CATEGORIES))


#: ``tables/grounding``: one row per compared method (Table 2).
GROUNDING_SPEC = TableSpec(
    "grounding", "Grounding: accuracy and vIoU per category", "method",
    _score_columns("method", "the grounding method (display name)"), keys=("method",),
    schema_name="grounding_method", printed=("method", *GROUNDING_COLUMNS),
    headlines=(Headline("total_acc"), Headline("total_viou")))
#: ``tables/grounding_ablation``: one row per feature set of this method (Table 3).
ABLATION_SPEC = TableSpec(
    "grounding_ablation", "Grounding: feature ablation", "feature set",
    _score_columns("features", f"the node features used, one of {', '.join(ABLATION_ROWS)}"), keys=("features",),
    schema_name="grounding_features", printed=("features", *GROUNDING_COLUMNS), headlines=(Headline("total_acc"),))


def _ours(table: pa.Table) -> list[int]:
    return [k for k, m in enumerate(table["method"].to_pylist()) if m == "ours"]


#: ``tables/grounding_outcomes``: every method's answer to every query (Markdown: this method's answers).
OUTCOMES_SPEC = TableSpec(
    "grounding_outcomes", "Grounding: every answer", "(method, query)", (
        Column("method", pa.string(), "the grounding method (key)"),
        Column("seq_id", pa.string(), "the sequence asked about"),
        Column("query_id", pa.string(), "the query's id in the benchmark"),
        Column("text", pa.string(), "the query text"),
        Column("style", pa.string(), "its paraphrase style"),
        Column("kind", pa.string(), "single | group | none (matches no object)"),
        Column("category", pa.string(), "vehicle | pedestrian"),
        Column("targets", pa.list_(pa.string()), "the object ids the query describes"),
        Column("predicted", pa.list_(pa.string()), "the object ids the method answered"),
        Column("correct", pa.bool_(), "predicted == targets"),
        Column("viou", pa.float64(), "video IoU of the predicted masks", "share"),
        Column("seconds", pa.float64(), "wall time of the answer", "s"),
    ), keys=("method", "seq_id", "query_id"), printed=("seq_id", "text", "kind", "correct", "viou"),
    row_filter=_ours, detail=True)


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


def grounding_outcomes_table(results: GroundingResults) -> pa.Table:
    """Every method's answer to every query (:data:`OUTCOMES_SPEC`)."""
    rows = [{"method": o.method, "seq_id": o.query.seq_id, "query_id": o.query.query_id, "text": o.query.text,
             "style": o.query.style, "kind": o.query.kind, "category": o.query.category,
             "targets": list(o.query.target_ids), "predicted": list(o.predicted), "correct": bool(o.correct),
             "viou": float(o.viou), "seconds": float(o.seconds)} for o in results.outcomes]
    return OUTCOMES_SPEC.table(rows)


__all__ = ["ABLATION_ROWS", "ABLATION_SPEC", "GROUNDING_COLUMNS", "GROUNDING_SPEC", "OUTCOMES_SPEC", "ablation_table",
           "grounding_outcomes_table", "grounding_table"]
