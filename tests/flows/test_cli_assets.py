"""``simsplat assets build | list | sheet``."""

from __future__ import annotations

import json

import cv2
import pytest
from typer.testing import CliRunner

from flows.cli import app
from tests.simsplat_core.editing.assets.fixtures import tiny_store

runner = CliRunner()


@pytest.mark.parametrize("command", [["assets"], ["assets", "build"], ["assets", "list"], ["assets", "sheet"]])
def test_assets_commands_have_help(command) -> None:
    result = runner.invoke(app, [*command, "--help"])
    assert result.exit_code == 0, result.output
    assert "Usage" in result.output


def test_list_on_a_store_without_banks_says_how_to_build_one(tmp_path) -> None:
    result = runner.invoke(app, ["assets", "list", "--store", str(tmp_path)])
    assert result.exit_code != 0
    assert "simsplat assets build" in result.output


def test_build_names_a_sequence_without_a_scene(tmp_path) -> None:
    result = runner.invoke(app, ["assets", "build", "--store", str(tmp_path), "--seq", "synth-000042"])
    assert result.exit_code != 0
    assert "synth-000042" in result.output


def test_build_list_and_sheet(tmp_path) -> None:
    root, _ = tiny_store(tmp_path / "store")
    built = runner.invoke(app, ["assets", "build", "--store", root, "--no-sheet", "--json"])
    assert built.exit_code == 0, built.output
    info = json.loads(built.output)
    assert info["assets"] >= 20 and not info["skipped"] and info["sheet"] is None
    listed = runner.invoke(app, ["assets", "list", "--store", root, "--json"])
    assert listed.exit_code == 0, listed.output
    index = json.loads(listed.output)
    assert index["bank_hash"] == info["bank_hash"] and len(index["assets"]) == info["assets"]
    assert "proc.traffic-cone.orange" in {a["asset_id"] for a in index["assets"]}
    table = runner.invoke(app, ["assets", "list", "--store", root], env={"COLUMNS": "240"})
    assert table.exit_code == 0 and "an orange traffic cone" in table.output
    out = tmp_path / "sheet.png"
    sheet = runner.invoke(app, ["assets", "sheet", "--store", root, "--out", str(out), "--columns", "5"])
    assert sheet.exit_code == 0, sheet.output
    picture = cv2.imread(str(out))
    assert picture is not None and picture.shape[1] == 5 * 180 and picture.shape[0] >= 4 * 180
