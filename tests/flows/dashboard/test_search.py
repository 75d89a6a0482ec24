"""The search page without a browser: a description answered over every log with ranked hits, frame windows, the
objects that matched and pictures made in memory (nothing written to ``searches/``); a log that does not read is
named and the others are still searched."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def test_an_empty_search_asks_for_a_description(client: TestClient) -> None:
    view = client.get("/api/search").json()
    assert view["query"] == "" and view["answer"] is None and view["logs"]["value"] == 1
    assert 'name="q"' in client.get("/search").text


def test_a_search_ranks_hits_with_windows_and_pictures(client: TestClient, dashboard_store: DashboardStore) -> None:
    answer = client.get("/api/search", params={"q": "a pedestrian walking", "top": 2}).json()["answer"]
    assert answer["error"] == ""
    found = answer["value"]
    assert found["total_hits"] >= len(found["hits"]) >= 1 and len(found["hits"]) <= 2
    assert [h["rank"] for h in found["hits"]] == list(range(1, len(found["hits"]) + 1))
    scores = [h["score"] for h in found["hits"]]
    assert scores == sorted(scores, reverse=True)
    for hit in found["hits"]:
        assert hit["seq_id"] == dashboard_store.seq_id and 0 <= hit["window"][0] <= hit["window"][1] <= 5
        assert hit["objects"][0]["category"] == "pedestrian" and hit["picture_kind"] == "cameras"
        picture = client.get(f"/files/{hit['picture']}")
        assert picture.status_code == 200 and picture.content.startswith(b"\x89PNG")
    assert [(r["seq_id"], r["hits"]) for r in found["logs"]] == [(dashboard_store.seq_id, found["total_hits"])]
    page = client.get("/search", params={"q": "a pedestrian walking"})
    assert page.status_code == 200 and page.text.count('class="hit"') == min(found["total_hits"], 10)
    assert not (Path(dashboard_store.root) / "searches").exists()  # read only


def test_a_description_nothing_matches_says_why(client: TestClient) -> None:
    found = client.get("/api/search", params={"q": "a cyclist turning left"}).json()["answer"]["value"]
    assert found["hits"] == [] and found["message"].startswith("no log matches")


def test_an_unreadable_log_is_named_and_left_out(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    root = tmp_path / "store"
    shutil.copytree(dashboard_store.root, root)
    (root / "logs" / dashboard_store.seq_id / "tracks.parquet").write_bytes(b"garbage")
    found = TestClient(create_app(DashboardSettings(str(root)))).get(
        "/api/search", params={"q": "a pedestrian"}).json()["answer"]["value"]
    assert found["hits"] == [] and len(found["unreadable"]) == 1 and "tracks.parquet" in found["unreadable"][0]
