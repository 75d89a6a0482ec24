"""``simsplat search`` and ``simsplat eval search`` on a small store of image-less synthetic logs."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from flows.cli import app
from simsplat_core.world.config import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import ArtifactStore, write_scene_log

runner = CliRunner()


@pytest.fixture(scope="module")
def store(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("search_store")
    config = WorldConfig(num_frames=30, render_images=False)
    for seed in (61, 62):
        write_scene_log(ArtifactStore(str(root)), generate_log(seed=seed, config=config))
    return root


def test_search_json_lists_windows_and_bev_pictures(store: Path, tmp_path: Path) -> None:
    result = runner.invoke(app, ["search", "--store", str(store), "--out", str(tmp_path), "--top", "2", "--json",
                                 "someone crossing the street"])
    assert result.exit_code == 0, result.output
    answer = json.loads(result.output)
    assert answer["clauses"] == ["someone crossing the street"] and len(answer["hits"]) == 2
    for hit in answer["hits"]:
        start, end = hit["window"]
        assert hit["seq_id"] in ("synth-000061", "synth-000062") and 0 <= start <= end < 30
        assert hit["object_ids"] and 0 < hit["score"] <= 1
        assert hit["picture_kind"] == "bev" and Path(hit["picture"]).is_file()  # logs without images


def test_search_negative_says_why(store: Path) -> None:
    result = runner.invoke(app, ["search", "--store", str(store), "--json", "a pedestrian on the highway shoulder"])
    answer = json.loads(result.output)
    assert answer["hits"] == [] and "the map has no highway" in answer["message"]


def test_eval_search_writes_the_table(store: Path, tmp_path: Path) -> None:
    result = runner.invoke(app, ["eval", "search", "--store", str(store), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    table = pq.read_table(tmp_path / "tables" / "search.parquet")
    assert table.column_names[:6] == ["query", "negative", "timestamp_ba", "log_ba", "hits", "logs_true"]
    rows = table.to_pylist()
    assert len(rows) >= 30 and sum(r["negative"] for r in rows) >= 8
    assert (tmp_path / "tables" / "search.md").is_file()
