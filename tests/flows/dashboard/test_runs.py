"""The runs pages without a browser: the list with every run folder (recorded, running, garbled, evaluation-only),
a run's matrix with status, seconds, retries and the error of a failed stage, the live fragment, the JSON twins,
unknown runs and unsafe names as 404."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from storage import ArtifactStore
from storage.run_records import stage_record_relpath
from tests.flows.dashboard.run_records_fixture import FAILED_SEQ, FAILURE, GARBLED_RUN, LIVE_RUN
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def test_the_runs_list_has_every_run_folder(client: TestClient, dashboard_store: DashboardStore) -> None:
    body = client.get("/api/runs").json()
    assert body["runs"]["error"] == ""
    runs = {r["run_id"]: r for r in body["runs"]["value"]}
    assert {dashboard_store.mining_run, LIVE_RUN, GARBLED_RUN} <= set(runs)
    mined = runs[dashboard_store.mining_run]
    assert mined["status"] == "completed" and mined["code_version"] == "v0.1-test"
    assert mined["counts"]["accepted_scenarios"] == dashboard_store.mining.accepted and mined["seconds"] > 30
    assert runs[LIVE_RUN]["status"] == "running"
    assert runs[GARBLED_RUN]["status"] == "unreadable" and "not valid JSON" in runs[GARBLED_RUN]["problem"]
    assert list(runs)[0] == LIVE_RUN  # newest start first
    page = client.get("/runs")
    assert page.status_code == 200
    assert f'href="/runs/{dashboard_store.mining_run}"' in page.text and "not valid JSON" in page.text


def test_a_run_page_shows_its_matrix(client: TestClient, dashboard_store: DashboardStore) -> None:
    body = client.get(f"/api/runs/{dashboard_store.mining_run}").json()
    assert body["live"] is False and body["record"]["value"]["parameters"]["seeds"] == [0]
    matrix = body["matrix"]["value"]
    assert matrix["stages"][:6] == ["ingest", "reconstruct", "align", "mine", "evaluate", "export"]
    (row,) = matrix["rows"]
    cells = dict(zip(matrix["stages"], row["cells"]))
    assert cells["align"]["status"] == "completed" and cells["align"]["retries"] == 1
    assert cells["evaluate"]["status"] == "skipped" and cells["evaluate"]["skip_reason"]
    page = client.get(f"/runs/{dashboard_store.mining_run}")
    assert page.status_code == 200 and "1 retry" in page.text and "evaluation not requested" in page.text
    assert "data-live=\"false\"" in page.text


def test_a_running_run_refreshes_and_shows_a_failed_stages_error(client: TestClient) -> None:
    page = client.get(f"/runs/{LIVE_RUN}")
    assert page.status_code == 200
    assert f'data-refresh="/runs/{LIVE_RUN}/matrix"' in page.text and 'data-live="true"' in page.text
    assert FAILURE in page.text
    fragment = client.get(f"/runs/{LIVE_RUN}/matrix")
    assert fragment.status_code == 200 and "<html" not in fragment.text
    assert 'data-live="true"' in fragment.text and FAILED_SEQ in fragment.text
    cells = client.get(f"/api/runs/{LIVE_RUN}").json()["matrix"]["value"]["rows"]
    failed = next(r for r in cells if r["seq_id"] == FAILED_SEQ)["cells"][0]
    assert (failed["status"], failed["retries"], failed["error"]) == ("failed", 1, FAILURE)


def test_a_garbled_run_record_shows_a_message_and_the_rest_of_the_page(client: TestClient) -> None:
    body = client.get(f"/api/runs/{GARBLED_RUN}").json()
    assert "not valid JSON" in body["record"]["error"] and body["matrix"]["error"] == ""
    page = client.get(f"/runs/{GARBLED_RUN}")
    assert page.status_code == 200 and "not valid JSON" in page.text and "Evaluation tables" in page.text


def test_a_garbled_stage_record_is_named_on_its_run_page(tmp_path) -> None:
    store = ArtifactStore(tmp_path)
    store.write_json("runs/r1/run.json", {"run_id": "r1", "flow": "simsplat-main", "status": "completed",
                                          "started_at": "2026-01-01T00:00:00+00:00"})
    store.write_bytes(stage_record_relpath("r1", "synth-000001", "mine", "completed"), b"\x00garbage")
    client = TestClient(create_app(DashboardSettings(str(tmp_path))))
    page = client.get("/runs/r1")
    assert page.status_code == 200 and "unreadable stage record" in page.text and "mine-completed.json" in page.text


def test_an_evaluation_only_run_shows_its_manifest_and_tables(tmp_path) -> None:
    store = ArtifactStore(tmp_path)
    store.write_json("runs/eval-1/manifest.json", {"stage": "grounding", "queries": 103,
                                                   "written_at": "2026-01-01T00:00:00+00:00"})
    store.write_bytes("runs/eval-1/tables/grounding.parquet", b"PAR1")
    store.write_bytes("runs/eval-1/tables/grounding.md", b"| a |\n")
    client = TestClient(create_app(DashboardSettings(str(tmp_path))))
    (run,) = client.get("/api/runs").json()["runs"]["value"]
    assert (run["status"], run["counts"], run["tables"]) == ("tables only", {"queries": 103}, ["grounding"])
    body = client.get("/api/runs/eval-1").json()
    assert body["record"]["value"] is None and body["manifest"]["value"]["queries"] == 103
    (table,) = body["tables"]["value"]
    assert table["href"] == "/evaluation?run=eval-1#grounding"
    assert client.get(f"/files/{table['markdown_id']}").text == "| a |\n"
    page = client.get("/runs/eval-1")
    assert page.status_code == 200 and "no run record" in page.text and "grounding" in page.text


def test_an_empty_store_lists_no_runs(tmp_path) -> None:
    client = TestClient(create_app(DashboardSettings(str(tmp_path / "nowhere"))))
    assert client.get("/api/runs").json()["runs"] == {"name": "runs", "value": [], "error": ""}
    assert "No runs yet" in client.get("/runs").text


@pytest.mark.parametrize("run_id", ["no-such-run", "%2E%2E", "..%2Fetc", "-dash"])
def test_unknown_runs_are_404(client: TestClient, run_id: str) -> None:
    assert client.get(f"/runs/{run_id}").status_code == 404
    assert "error" in client.get(f"/api/runs/{run_id}").json()
    assert client.get(f"/runs/{run_id}/matrix").status_code == 404
