"""The mining pages and the scenario card without a browser: the funnel and the scenario list match the run's edits
table, filters narrow the list, the card shows its parts (with the judge's reasons), unknown or unsafe names get
404, and a corrupt edits table or a missing validation.json shows a message on the page it affects."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from simsplat_core.eval.mining_funnel import FUNNEL_STAGES, stage_reached
from storage import ArtifactStore
from storage.edits import edit_dir, edits_table_relpath, read_edit_records
from storage.schemas.edits import EDITS_MINING_COLUMNS
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def _rows(store: DashboardStore) -> list[dict[str, Any]]:
    records = read_edit_records(ArtifactStore(store.root), store.mining_run)
    return [{**r.__dict__, **{k: r.mining.get(k) for k in EDITS_MINING_COLUMNS}} for r in records]


def _accepted(store: DashboardStore) -> list[str]:
    return [s.edit_id for s in store.mining.scenarios]


def test_the_index_lists_the_mining_run(client: TestClient, dashboard_store: DashboardStore) -> None:
    runs = client.get("/api/mining").json()["runs"]["value"]
    (entry,) = [r for r in runs if r["value"]["run_id"] == dashboard_store.mining_run]
    summary = entry["value"]
    assert summary["mined"] and summary["attempts"] == dashboard_store.mining.attempts
    assert summary["accepted"] == dashboard_store.mining.accepted
    page = client.get("/mining")
    assert page.status_code == 200 and f'href="/mining/{dashboard_store.mining_run}"' in page.text


def test_the_funnel_matches_the_edits_table(client: TestClient, dashboard_store: DashboardStore) -> None:
    rows = _rows(dashboard_store)
    content = client.get(f"/api/mining/{dashboard_store.mining_run}").json()["content"]["value"]
    total = content["funnel"][-1]
    assert total["category"] == "total"
    reached = [FUNNEL_STAGES.index(stage_reached(r)) for r in rows]
    assert total["attempts"] == [sum(k >= s for k in reached) for s in range(len(FUNNEL_STAGES))]
    assert total["proposals"][0] == len({(r["seq_id"], r["scenario"]) for r in rows})
    assert total["proposals"][-1] == dashboard_store.mining.accepted == content["summary"]["accepted"]
    failed = [r for r in rows if r["failure_reason"]]
    assert sum(f["attempts"] for f in content["failures"]) >= len(failed)
    assert sum(content["attempts_to_acceptance"]["counts"]) == dashboard_store.mining.accepted
    judged = [r for r in rows if r["plausibility"] is not None]
    assert sum(content["plausibility"]["counts"]) == len(judged)
    assert {s["edit_id"] for s in content["scenarios"] if s["status"] == "accepted"} == set(_accepted(dashboard_store))
    page = client.get(f"/mining/{dashboard_store.mining_run}")
    assert page.status_code == 200
    for edit_id in _accepted(dashboard_store):
        assert f"/scenarios/{dashboard_store.mining_run}/{dashboard_store.seq_id}/{edit_id}" in page.text


def test_filters_narrow_the_scenario_list(client: TestClient, dashboard_store: DashboardStore) -> None:
    url = f"/api/mining/{dashboard_store.mining_run}"
    every = client.get(url).json()["content"]["value"]["scenarios"]
    accepted = client.get(url, params={"status": "accepted"}).json()["content"]["value"]["scenarios"]
    assert len(accepted) == dashboard_store.mining.accepted < len(every)
    category = accepted[0]["category"]
    chosen = client.get(url, params={"category": category, "min_plausibility": "1"}).json()["content"]["value"]
    assert chosen["scenarios"] and all(s["category"] == category and s["plausibility"] >= 1
                                       for s in chosen["scenarios"])
    none = client.get(url, params={"sequence": "no-such-log", "min_plausibility": ""}).json()["content"]["value"]
    assert none["scenarios"] == [] and none["total"] == len(every)
    assert client.get(f"/mining/{dashboard_store.mining_run}", params={"status": "accepted"}).status_code == 200


def test_the_card_shows_every_part(client: TestClient, dashboard_store: DashboardStore) -> None:
    scenario = dashboard_store.mining.scenarios[0]
    url = f"/scenarios/{dashboard_store.mining_run}/{dashboard_store.seq_id}/{scenario.edit_id}"
    card = client.get("/api" + url).json()
    for name in ("attempts", "verdict", "program", "pictures", "motion", "validation", "exports"):
        assert card[name]["error"] == "", (name, card[name]["error"])
    assert card["prompt"] == scenario.prompt and card["status"] == "accepted" and card["stored"]
    assert card["verdict"]["value"]["reasons"]  # the judge's reasons, kept in the edits table
    assert card["program"]["value"]["commands"] and card["program"]["value"]["source"] == "command.json"
    pictures = card["pictures"]["value"]
    assert pictures["cameras"] and all(p["before"] and p["after"] for c in pictures["cameras"] for p in c["frames"])
    assert client.get(f"/files/{pictures['cameras'][0]['frames'][0]['after']}").content[:4] == b"\x89PNG"
    bev = card["motion"]["value"]["bev"]
    assert len(bev["frames"]) == len(bev["times"]) and any(a["source"] != "log" for a in bev["agents"])
    assert all(len(a["edited"]) in (0, len(bev["frames"])) for a in bev["agents"])
    assert [d["name"] for d in card["exports"]["value"]] == [dashboard_store.dataset]
    assert [a["attempt"] for a in card["attempts"]["value"]] == list(range(1, len(card["attempts"]["value"]) + 1))
    page = client.get(url)
    assert page.status_code == 200 and scenario.prompt in page.text and 'id="bev"' in page.text


@pytest.mark.parametrize("path", ["/scenarios/mine-dash/synth-000000/0000000000000000", "/scenarios/nope/a/b",
                                  "/scenarios/mine-dash/..%2F..%2Fetc/passwd", "/mining/no-such-run",
                                  "/mining/..%2F..", "/api/scenarios/mine-dash/.hidden/x"])
def test_unknown_or_unsafe_names_are_not_found(client: TestClient, path: str) -> None:
    assert client.get(path).status_code == 404


def _broken_copy(dashboard_store: DashboardStore, tmp_path: Path) -> Path:
    root = tmp_path / "store"
    shutil.copytree(dashboard_store.root, root)
    return root


def test_a_corrupt_edits_table_is_said_on_its_pages(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    root = _broken_copy(dashboard_store, tmp_path)
    for part in (root / edits_table_relpath(dashboard_store.mining_run)).iterdir():
        part.write_bytes(b"PAR1 not parquet")
    client = TestClient(create_app(DashboardSettings(str(root))))
    (entry,) = client.get("/api/mining").json()["runs"]["value"]
    assert "not a readable Parquet file" in entry["error"] and "edits.parts" in entry["error"]
    run = client.get(f"/mining/{dashboard_store.mining_run}")
    assert run.status_code == 200 and "not a readable Parquet file" in run.text and 'role="alert"' in run.text
    edit_id = dashboard_store.mining.scenarios[0].edit_id
    card = client.get(f"/api/scenarios/{dashboard_store.mining_run}/{dashboard_store.seq_id}/{edit_id}").json()
    assert "not a readable Parquet file" in card["attempts"]["error"]
    assert card["validation"]["error"] == "" and card["pictures"]["error"] == ""  # the rest still shows


def test_a_missing_validation_is_said_on_the_card(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    root = _broken_copy(dashboard_store, tmp_path)
    edit_id = dashboard_store.mining.scenarios[0].edit_id
    (root / edit_dir(dashboard_store.mining_run, dashboard_store.seq_id, edit_id) / "validation.json").unlink()
    client = TestClient(create_app(DashboardSettings(str(root))))
    url = f"/scenarios/{dashboard_store.mining_run}/{dashboard_store.seq_id}/{edit_id}"
    card = client.get("/api" + url).json()
    assert "validation.json" in card["validation"]["error"] and card["motion"]["error"] == ""
    page = client.get(url)
    assert page.status_code == 200 and "no validation.json" in page.text
