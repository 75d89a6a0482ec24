"""``simsplat eval all``: the tables a store allows, printed from their declarations; skips and bad input named."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from flows.cli import app
from simsplat_core.world.config import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import ArtifactStore, write_scene_log


@pytest.fixture(scope="module")
def image_less_store(tmp_path_factory: pytest.TempPathFactory) -> str:
    root = tmp_path_factory.mktemp("eval_all_cli")
    write_scene_log(ArtifactStore(str(root)), generate_log(seed=71, config=WorldConfig(num_frames=30,
                                                                                         render_images=False)))
    return str(root)


def test_eval_all_prints_the_search_table_and_the_skipped_evaluations(image_less_store: str, tmp_path) -> None:
    result = CliRunner().invoke(app, ["eval", "all", "--store", image_less_store, "--out", str(tmp_path),
                                      "--only", "search,grounding"])
    assert result.exit_code == 0, result.output
    assert "Search: RefAV balanced accuracies" in result.output
    assert "skipped grounding: no aligned synthetic log with ground-truth images" in result.output
    assert (tmp_path / "summary.md").exists() and (tmp_path / "tables" / "search.parquet").exists()


def test_eval_all_json_is_one_object(image_less_store: str, tmp_path) -> None:
    result = CliRunner().invoke(app, ["eval", "all", "--store", image_less_store, "--out", str(tmp_path),
                                      "--only", "reconstruction", "--json"])
    assert result.exit_code == 0, result.output
    answer = json.loads(result.stdout)
    assert answer["tables"] == {} and answer["skipped"] == {"reconstruction": "no reconstructed scene"}


def test_eval_all_names_an_unknown_evaluation(image_less_store: str, tmp_path) -> None:
    result = CliRunner().invoke(app, ["eval", "all", "--store", image_less_store, "--out", str(tmp_path),
                                      "--only", "nope"])
    assert result.exit_code == 2
    assert "nope" in result.output
