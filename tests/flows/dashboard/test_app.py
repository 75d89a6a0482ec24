"""The app without a browser: the overview and its JSON twin, files only by artifact id (a path or an unknown id
gets 404), a missing store said plainly, the token guard and the refusal of a non-loopback address without one."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings, UnsafeBindError
from storage.artifact_ids import artifact_id
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def test_overview_counts_what_the_store_holds(client: TestClient) -> None:
    counts = client.get("/api").json()["counts"]
    assert counts["error"] == "" and counts["value"]["logs"] == 1 and counts["value"]["datasets"] == 1
    page = client.get("/")
    assert page.status_code == 200 and "<b>1</b> logs" in page.text


@pytest.mark.parametrize("path", ["/files/..%2F..%2Fetc%2Fpasswd", "/files/%2Fetc%2Fpasswd", "/files/logs-..",
                                  "/files/logs/synth-000000/frames.parquet", "/files/edits-" + "0" * 24,
                                  "/files/etc-0123456789abcdef01234567"])
def test_files_are_served_by_id_only(client: TestClient, path: str) -> None:
    assert client.get(path).status_code == 404


def test_a_stored_render_is_served_as_png_by_its_id(client: TestClient, dashboard_store: DashboardStore) -> None:
    aid = artifact_id(f"logs/{dashboard_store.seq_id}/images/front/000000.exr")
    response = client.get(f"/files/{aid}")
    assert response.status_code == 200 and response.headers["content-type"] == "image/png"
    assert response.content[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_missing_store_is_said_plainly(tmp_path) -> None:
    client = TestClient(create_app(DashboardSettings(str(tmp_path / "nowhere"))))
    body = client.get("/api").json()
    assert body["exists"] is False and "does not exist" in body["counts"]["error"]
    assert not (tmp_path / "nowhere").exists()  # read only: nothing created


def test_the_token_is_required_when_set(dashboard_store: DashboardStore) -> None:
    client = TestClient(create_app(DashboardSettings(dashboard_store.root, token="s3cret")))
    assert client.get("/api").status_code == 401
    assert client.get("/api", headers={"Authorization": "Bearer wrong"}).status_code == 401
    assert client.get("/api", headers={"Authorization": "Bearer s3cret"}).status_code == 200
    assert client.get("/?token=s3cret").status_code == 200
    assert client.get("/api").status_code == 200  # the cookie the tokened request set


def test_a_non_loopback_address_needs_a_token(tmp_path) -> None:
    with pytest.raises(UnsafeBindError, match="needs a token"):
        DashboardSettings(str(tmp_path), host="0.0.0.0")
    assert "s3cret" not in repr(DashboardSettings(str(tmp_path), host="0.0.0.0", token="s3cret"))


@pytest.mark.parametrize("state", ["missing", "empty"])
@pytest.mark.parametrize("path", ["/", "/runs", "/sequences", "/search?q=a+red+car", "/mining", "/evaluation",
                                  "/datasets"])
def test_every_page_group_answers_on_a_missing_or_empty_store(tmp_path, state: str, path: str) -> None:
    root = tmp_path / "store"
    if state == "empty":
        root.mkdir()
    client = TestClient(create_app(DashboardSettings(str(root))))
    page = client.get(path)
    assert page.status_code == 200 and "<h1>" in page.text
    twin = client.get("/api" + path if path != "/" else "/api")
    assert twin.status_code == 200 and isinstance(twin.json(), dict)
    assert root.exists() == (state == "empty") and (state == "missing" or not any(root.iterdir()))
