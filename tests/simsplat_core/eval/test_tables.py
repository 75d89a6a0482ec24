"""Grounding table builders: columns, row order, Markdown."""

from __future__ import annotations

import math

import pyarrow as pa
import pytest

from simsplat_core.eval.grounding.metrics import CategoryScore
from simsplat_core.eval.grounding.tables import GROUNDING_COLUMNS, GROUNDING_SPEC, ablation_table, grounding_table
from simsplat_core.eval.table_spec import markdown


def _summary() -> dict:
    def scores(acc: float, v: float) -> dict:
        return {
            "vehicle": CategoryScore(10, acc, v),
            "pedestrian": CategoryScore(5, acc / 2, v / 2),
            "total": CategoryScore(15, acc * 0.8, v * 0.8),
        }

    return {"app": scores(0.5, 0.4), "frames": scores(0.6, 0.55), "ours": scores(0.95, 0.9),
            "empty": {c: CategoryScore(0, math.nan, math.nan) for c in ("vehicle", "pedestrian", "total")}}


def test_grounding_table_columns_and_order() -> None:
    t = grounding_table(_summary(), {"Ours": "ours", "LangSplat-like": "app"})
    assert t.column_names[0] == "method"
    assert tuple(t.column_names[1:7]) == GROUNDING_COLUMNS
    assert t.column("method").to_pylist() == ["Ours", "LangSplat-like"]
    assert t.column("vehicle_acc").to_pylist() == [0.95, 0.5]
    assert t.column("pedestrian_viou").to_pylist() == pytest.approx([0.45, 0.2])
    assert t.column("total_queries").to_pylist() == [15, 15]
    assert t.schema.field("total_acc").type == pa.float64()
    assert t.schema.field("vehicle_queries").type == pa.int64()


def test_missing_method_is_named() -> None:
    with pytest.raises(KeyError, match="nope"):
        grounding_table(_summary(), {"X": "nope"})


def test_ablation_table_rows() -> None:
    t = ablation_table(_summary(), {"App": "app", "All": "ours"})
    assert t.column_names[0] == "features"
    assert t.column("features").to_pylist() == ["App", "All"]
    with pytest.raises(ValueError, match="ablation rows"):
        ablation_table(_summary(), {"Appearance": "app"})


def test_markdown_layout() -> None:
    t = grounding_table(_summary(), {"Ours": "ours", "none": "empty"})
    md = GROUNDING_SPEC.render_markdown(t, digits=2)
    lines = md.strip().splitlines()
    assert lines[0] == "| method | " + " | ".join(GROUNDING_COLUMNS) + " |"
    assert lines[1].startswith("|:---|---:")
    assert lines[2] == "| Ours | 0.95 | 0.90 | 0.47 | 0.45 | 0.76 | 0.72 |"
    assert lines[3].startswith("| none | – | –")
    full = markdown(t)
    assert "total_queries" in full.splitlines()[0]
    with pytest.raises(KeyError, match="no columns"):
        markdown(t, columns=("method", "recall"))
