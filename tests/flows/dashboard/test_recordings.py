"""Scenarios as Rerun recordings: the ``.rrd`` written by ``tasks.rerun_export`` (read back with rerun's own
reader: the map, the agents' boxes and paths, every camera), the dashboard's download and ``simsplat
export-rerun``. Skipped without the optional rerun-sdk package, except the refusal that says it is missing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

import tasks.rerun_export as rerun_export
from flows.cli import app
from flows.dashboard.app import create_app
from flows.dashboard.pages.recordings import recording_url
from flows.dashboard.settings import DashboardSettings
from storage import ArtifactStore
from storage.edits import list_edits
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def edit_id(dashboard_store: DashboardStore) -> str:
    edits = list_edits(ArtifactStore(dashboard_store.root), dashboard_store.mining_run, dashboard_store.seq_id)
    assert edits, "the test store's mining run stored no scenario"
    return edits[0]


def _entities(path: Path) -> set[str]:
    """Entity paths of a recording, read back by rerun's own reader."""
    chunk = pytest.importorskip("rerun.chunk")
    return set(chunk.RrdReader(path).store().schema().entity_paths())


def test_a_scenario_recording_holds_the_map_agents_paths_and_cameras(dashboard_store: DashboardStore, edit_id: str,
                                                                     tmp_path: Path) -> None:
    pytest.importorskip("rerun")
    out = tmp_path / "scenario.rrd"
    summary = rerun_export.write_scenario_recording(dashboard_store.root, dashboard_store.mining_run,
                                                    dashboard_store.seq_id, edit_id, str(out))
    assert out.stat().st_size == summary.bytes > 0
    assert summary.cameras and summary.images == summary.frames * len(summary.cameras)
    entities = _entities(out)
    assert {"/world/agents", "/world/paths/log", "/world/paths/scenario", "/scenario"} <= entities
    assert any(e.startswith("/world/map/") for e in entities)
    assert {f"/world/cameras/{c}" for c in summary.cameras} <= entities
    assert {"/" + e for e in summary.entities} == entities


def test_the_dashboard_serves_a_scenarios_recording(dashboard_store: DashboardStore, edit_id: str,
                                                    tmp_path: Path) -> None:
    pytest.importorskip("rerun")
    client = TestClient(create_app(DashboardSettings(dashboard_store.root)))
    response = client.get(recording_url(dashboard_store.mining_run, dashboard_store.seq_id, edit_id))
    assert response.status_code == 200 and "attachment" in response.headers["content-disposition"]
    (tmp_path / "download.rrd").write_bytes(response.content)
    assert "/world/agents" in _entities(tmp_path / "download.rrd")
    card = client.get(f"/scenarios/{dashboard_store.mining_run}/{dashboard_store.seq_id}/{edit_id}")
    assert f'href="{recording_url(dashboard_store.mining_run, dashboard_store.seq_id, edit_id)}"' in card.text


@pytest.mark.parametrize("edit", ["0" * 16, "..%2F..%2Fetc"])
def test_an_unknown_scenario_has_no_recording(dashboard_store: DashboardStore, edit: str) -> None:
    pytest.importorskip("rerun")
    client = TestClient(create_app(DashboardSettings(dashboard_store.root)))
    assert client.get(recording_url(dashboard_store.mining_run, dashboard_store.seq_id, edit)).status_code == 404


def test_without_rerun_the_download_says_what_to_install(dashboard_store: DashboardStore, edit_id: str,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    def missing() -> None:
        raise rerun_export.RerunUnavailableError("the Rerun export needs the rerun-sdk package")

    monkeypatch.setattr(rerun_export, "_rerun", missing)
    client = TestClient(create_app(DashboardSettings(dashboard_store.root)))
    response = client.get(recording_url(dashboard_store.mining_run, dashboard_store.seq_id, edit_id))
    assert response.status_code == 501 and "rerun-sdk" in response.json()["error"]


def test_the_cli_writes_a_recording_and_reports_it(dashboard_store: DashboardStore, edit_id: str,
                                                   tmp_path: Path) -> None:
    pytest.importorskip("rerun")
    out = tmp_path / "cli.rrd"
    args = ["export-rerun", "--store", dashboard_store.root, "--run", dashboard_store.mining_run,
            "--seq", dashboard_store.seq_id, "--edit", edit_id, "--out", str(out), "--json"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    reported = json.loads(result.stdout)
    assert reported["path"] == str(out) and reported["bytes"] == out.stat().st_size
    bad = CliRunner().invoke(app, [*args[:-3], "--edit", "0" * 16, "--out", str(tmp_path / "x.rrd")])
    assert bad.exit_code != 0 and "no complete edit" in bad.output and not (tmp_path / "x.rrd").exists()
