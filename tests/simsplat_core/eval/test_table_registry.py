"""The evaluation table declarations: every spec validates what its compute function returns, a missing column is
named with the file, and the Markdown and console renderings agree."""

from __future__ import annotations

import math
from collections.abc import Callable

import pyarrow as pa
import pytest

from simsplat_core.eval.editing.outcomes import completion_table, fidelity_table, infeasible_table, outcomes_table
from simsplat_core.eval.grounding.metrics import CategoryScore, GroundingResults
from simsplat_core.eval.grounding.tables import ablation_table, grounding_outcomes_table, grounding_table
from simsplat_core.eval.mining import mining_by_category_table, mining_stages_table, mining_table
from simsplat_core.eval.refinement.diagnosis import Stall, stalls_table
from simsplat_core.eval.refinement.table import MOTION_COLUMNS, motion_table
from simsplat_core.eval.refinement.table import outcomes_table as motion_outcomes_table
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from simsplat_core.eval.store_tables import SceneMetrics, StageTiming, reconstruction_table, throughput_table
from simsplat_core.eval.table_registry import EVAL_TABLES, table_spec
from simsplat_core.eval.table_spec import SCHEMA_NAME_KEY, SCHEMA_VERSION_KEY
from storage import ArtifactStore, SchemaError
from storage.runs import RunTable, write_run_tables
from storage.schemas import base
from storage.schemas.validation import validate_table

_SCORES = {c: CategoryScore(4, 0.5, 0.25) for c in ("vehicle", "pedestrian", "total")}
_MOTION_ROW = {n: 0.0 for n, _, _ in MOTION_COLUMNS} | {"dataset": "d", "method": "log", "predictor": "",
                                                          "scenarios": 1, "refused": 0, "ade_3s": None}

#: Each declared table built by the function that computes it (small inputs).
BUILDERS: dict[str, Callable[[], pa.Table]] = {
    "grounding": lambda: grounding_table({"ours": _SCORES}, {"Ours": "ours"}),
    "grounding_ablation": lambda: ablation_table({"ours": _SCORES}, {"All": "ours"}),
    "grounding_outcomes": lambda: grounding_outcomes_table(GroundingResults(outcomes=[])),
    "editing": lambda: completion_table([]),
    "editing_infeasible": lambda: infeasible_table([]),
    "edit_fidelity": lambda: fidelity_table([], {}),
    "editing_outcomes": lambda: outcomes_table([]),
    "motion": lambda: motion_table([_MOTION_ROW]),
    "motion_outcomes": lambda: motion_outcomes_table([]),
    "motion_stalls": lambda: stalls_table([Stall("waymo-motion", "s", 0, "7", "vehicle", 12, 20, "leader",
                                                 "9 (parked vehicle)", 3.5, 0.6)]),
    "mining": lambda: mining_table([], {}, {"rule": "", "openai": "not run: no endpoint"}),
    "mining_by_category": lambda: mining_by_category_table([], ["rule"]),
    "mining_stages": lambda: mining_stages_table({"rule": {"propose": 2.0, "judge": 1.0}}, {"rule": 1}, cores=2),
    "search": lambda: SEARCH_SPEC.table([{"query": "q", "negative": False, "timestamp_ba": None, "log_ba": 0.5,
                                          "hits": 1, "logs_true": 1, "logs_hit": 1, "seconds": 0.1}]),
    "reconstruction": lambda: reconstruction_table([SceneMetrics("s0", "abcdef0123456789", {"psnr_test": 27.0})]),
    "throughput": lambda: throughput_table([StageTiming("reconstruct", 2, 60.0), StageTiming("mine:judge", 3, 0.0)]),
}


def test_every_declared_table_has_a_builder_here() -> None:
    assert set(BUILDERS) == set(EVAL_TABLES)
    with pytest.raises(KeyError, match="no evaluation table 'nope'"):
        table_spec("nope")


def test_metadata_keys_agree_with_storage() -> None:
    assert (SCHEMA_NAME_KEY, SCHEMA_VERSION_KEY) == (base.SCHEMA_NAME_KEY, base.SCHEMA_VERSION_KEY)


@pytest.mark.parametrize("name", sorted(EVAL_TABLES))
def test_the_schema_validates_what_the_compute_function_returns(name: str) -> None:
    spec = table_spec(name)
    table = BUILDERS[name]()
    validate_table(table, spec.schema, name, require_metadata=False)
    assert spec.name == name and set(spec.keys) <= set(spec.column_names)
    assert all(c.meaning for c in spec.columns)
    assert spec.describe()["columns"][0]["name"] == spec.columns[0].name


@pytest.mark.parametrize("name", sorted(EVAL_TABLES))
def test_a_missing_column_is_named_with_the_file(tmp_path, name: str) -> None:
    spec = table_spec(name)
    column = spec.columns[-1].name
    table = BUILDERS[name]().drop_columns([column])
    with pytest.raises(SchemaError, match=rf"tables/{name}\.parquet.*'{column}' is missing"):
        write_run_tables(ArtifactStore(tmp_path), "run", {name: RunTable(table, spec.schema, "")})


@pytest.mark.parametrize("name", sorted(EVAL_TABLES))
def test_console_rows_follow_the_markdown(name: str) -> None:
    spec = table_spec(name)
    table = BUILDERS[name]()
    header, rows = spec.rows_for_console(table)
    lines = spec.render_markdown(table).splitlines()
    assert lines[0] == "| " + " | ".join(header) + " |"
    assert len(lines) == 2 + len(rows)


def test_throughput_sums_stages_and_leaves_rates_undefined_without_time() -> None:
    rows = {r["stage"]: r for r in BUILDERS["throughput"]().to_pylist()}
    assert rows["reconstruct"]["seconds_per_item"] == 30.0 and rows["reconstruct"]["items_per_hour"] == 120.0
    assert math.isnan(rows["mine:judge"]["items_per_hour"])
    with pytest.raises(ValueError, match="'align'"):
        throughput_table([StageTiming("align", -1, 1.0)])


def test_reconstruction_rows_fill_missing_metrics_with_nan() -> None:
    row = BUILDERS["reconstruction"]().to_pylist()[0]
    assert row["scene"] == "abcdef012345" and row["psnr_test"] == 27.0 and math.isnan(row["ssim_test"])
