"""Headline metrics and the paper's figures of table declarations: which rows a headline selects, how it labels
and reduces them, which cell a paper figure names, and declarations that name unknown columns refused."""

from __future__ import annotations

import math

import pyarrow as pa
import pytest

from simsplat_core.eval.table_headlines import Headline, PaperFigure, headline_values
from simsplat_core.eval.table_registry import EVAL_TABLES
from simsplat_core.eval.table_spec import Column, TableSpec

SPEC = TableSpec("t", "T", "(method, category)", (
    Column("method", pa.string(), "m"), Column("category", pa.string(), "c"),
    Column("rate", pa.float64(), "r", "share", nullable=True)), keys=("method", "category"))
TABLE = SPEC.table([{"method": "ours", "category": "a", "rate": 0.5},
                    {"method": "ours", "category": "total", "rate": 0.75},
                    {"method": "base", "category": "total", "rate": math.nan},
                    {"method": "other", "category": "total", "rate": None}])


def test_each_selected_row_is_a_series_labelled_by_its_free_keys() -> None:
    values = headline_values(Headline("rate", where=(("category", "total"),)), TABLE, SPEC.keys)
    assert values == [("ours", 0.75)]  # NaN and null left out
    everything = headline_values(Headline("rate"), TABLE, SPEC.keys)
    assert everything == [("ours / a", 0.5), ("ours / total", 0.75)]


def test_a_mean_headline_is_one_series_of_the_finite_values() -> None:
    assert headline_values(Headline("rate", reduce="mean"), TABLE, SPEC.keys) == [("mean", pytest.approx(0.625))]
    none = headline_values(Headline("rate", where=(("method", "base"),), reduce="mean"), TABLE, SPEC.keys)
    assert none == []


def test_a_paper_figure_names_one_cell() -> None:
    figure = PaperFigure("rate", 0.8, (("method", "ours"), ("category", "total")), "paper")
    assert figure.matching_value(TABLE) == 0.75
    assert PaperFigure("rate", 0.8, (("method", "nobody"),), "paper").matching_value(TABLE) is None


@pytest.mark.parametrize("extra", [{"headlines": (Headline("nope"),)},
                                   {"headlines": (Headline("rate", where=(("nope", "x"),)),)},
                                   {"paper": (PaperFigure("rate", 1.0, (("nope", "x"),), "paper"),)}])
def test_a_declaration_naming_unknown_columns_is_refused(extra: dict) -> None:
    with pytest.raises(ValueError, match="nope"):
        TableSpec("t", "T", "row", SPEC.columns, keys=SPEC.keys, **extra)


@pytest.mark.parametrize("kw", [{"reduce": "median"}, {"better": "more"}])
def test_a_headline_with_an_unknown_reduction_or_direction_is_refused(kw: dict) -> None:
    with pytest.raises(ValueError):
        Headline("rate", **kw)


def test_every_summary_table_with_numbers_declares_a_headline() -> None:
    summaries = [s for s in EVAL_TABLES.values() if not s.detail and s.name != "mining_by_category"]
    assert all(s.headlines for s in summaries), [s.name for s in summaries if not s.headlines]
