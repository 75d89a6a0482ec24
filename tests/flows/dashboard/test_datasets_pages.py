"""The datasets pages without a browser: every listed dataset with its manifest's counts, splits, formats and
shards; a manifest that disagrees with its files (a shard of another size, a missing shard, other bytes of the
same size found by ``?verify=1``, counts that do not add up) is flagged; an unknown dataset is a 404."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from storage.datasets import DATASETS_DIR, MANIFEST_NAME
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def _manifest(root: Path, name: str) -> dict:
    return json.loads((root / DATASETS_DIR / name / MANIFEST_NAME).read_text())


def test_the_listing_shows_each_dataset_matching_its_files(client: TestClient, dashboard_store: DashboardStore) -> None:
    body = client.get("/api/datasets").json()
    (entry,) = body["datasets"]["value"]
    summary = entry["value"]
    manifest = _manifest(Path(dashboard_store.root), dashboard_store.dataset)
    assert summary["name"] == dashboard_store.dataset and summary["problems"] == 0
    assert summary["scenarios"] == manifest["counts"]["scenarios"] > 0
    assert summary["shards"] == sum(len(i["shards"]) for i in manifest["increments"])
    page = client.get("/datasets")
    assert page.status_code == 200 and f'href="/datasets/{dashboard_store.dataset}"' in page.text
    assert "matches its files" in page.text


def test_a_dataset_page_shows_its_manifest_and_data_card(client: TestClient, dashboard_store: DashboardStore) -> None:
    body = client.get(f"/api/datasets/{dashboard_store.dataset}").json()
    manifest = _manifest(Path(dashboard_store.root), dashboard_store.dataset)
    m = body["manifest"]["value"]
    assert m["problems"] == [] and m["verified"] is False
    assert m["formats"] == manifest["formats"] and m["counts"] == manifest["counts"]
    assert {s["state"] for s in m["shards"]} == {"ok"}
    assert sorted(s["scenario_id"] for s in m["scenarios"]) == sorted(manifest["scenarios"])
    assert body["datacard"]["value"].startswith(f"# {dashboard_store.dataset}")
    verified = client.get(f"/api/datasets/{dashboard_store.dataset}?verify=1").json()["manifest"]["value"]
    assert verified["verified"] is True and {s["state"] for s in verified["shards"]} == {"verified"}
    page = client.get(f"/datasets/{dashboard_store.dataset}")
    assert page.status_code == 200 and "Verify every shard" in page.text and manifest["code_version"] in page.text


def _damaged_copy(source: DashboardStore, root: Path) -> tuple[TestClient, dict]:
    """A store holding a copy of the fixture's dataset (listing pointed at the copy); returns a client and the
    copied manifest."""
    shutil.copytree(Path(source.root) / DATASETS_DIR, root / DATASETS_DIR)
    listing = root / DATASETS_DIR / f"{source.dataset}.json"
    entry = json.loads(listing.read_text())
    listing.write_text(json.dumps({**entry, "uri": str(root / DATASETS_DIR / source.dataset)}))
    return TestClient(create_app(DashboardSettings(str(root)))), _manifest(root, source.dataset)


def test_a_shard_of_another_size_or_missing_is_flagged(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    client, manifest = _damaged_copy(dashboard_store, tmp_path)
    shards = manifest["increments"][0]["shards"]
    folder = tmp_path / DATASETS_DIR / dashboard_store.dataset
    (folder / shards[0]["path"]).write_bytes(b"truncated")
    (folder / shards[1]["path"]).unlink()
    body = client.get(f"/api/datasets/{dashboard_store.dataset}").json()["manifest"]["value"]
    states = {s["path"]: s["state"] for s in body["shards"]}
    assert states[shards[0]["path"]] == "size" and states[shards[1]["path"]] == "missing"
    assert any(shards[0]["path"] in line and "size" in line for line in body["problems"])
    summary = client.get("/api/datasets").json()["datasets"]["value"][0]["value"]
    assert summary["problems"] == len(body["problems"]) >= 2
    assert "the manifest disagrees with its files" in client.get(f"/datasets/{dashboard_store.dataset}").text


def test_other_bytes_of_the_same_size_are_found_only_when_verifying(dashboard_store: DashboardStore,
                                                                    tmp_path: Path) -> None:
    client, manifest = _damaged_copy(dashboard_store, tmp_path)
    shard = manifest["increments"][0]["shards"][0]
    path = tmp_path / DATASETS_DIR / dashboard_store.dataset / shard["path"]
    data = bytearray(path.read_bytes())
    data[-1] ^= 0xFF
    path.write_bytes(bytes(data))
    url = f"/api/datasets/{dashboard_store.dataset}"
    assert client.get(url).json()["manifest"]["value"]["problems"] == []  # cheap checks: size only
    verified = client.get(url + "?verify=1").json()["manifest"]["value"]
    assert {s["path"]: s["state"] for s in verified["shards"]}[shard["path"]] == "checksum"
    assert any("SHA-256" in line for line in verified["problems"])


def test_counts_that_do_not_add_up_are_flagged(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    client, manifest = _damaged_copy(dashboard_store, tmp_path)
    manifest["counts"]["scenarios"] += 1
    (tmp_path / DATASETS_DIR / dashboard_store.dataset / MANIFEST_NAME).write_text(json.dumps(manifest))
    checks = client.get(f"/api/datasets/{dashboard_store.dataset}").json()["manifest"]["value"]["count_checks"]
    differing = {c["what"] for c in checks if c["declared"] != c["found"]}
    assert "scenarios listed in the manifest" in differing and "scenarios of the increments" in differing


def test_a_missing_dataset_folder_is_said_in_its_place(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    client, _ = _damaged_copy(dashboard_store, tmp_path)
    shutil.rmtree(tmp_path / DATASETS_DIR / dashboard_store.dataset)
    (entry,) = client.get("/api/datasets").json()["datasets"]["value"]
    assert entry["value"] is None and "no manifest.json" in entry["error"]
    page = client.get(f"/datasets/{dashboard_store.dataset}")
    assert page.status_code == 200 and "no manifest.json" in page.text


@pytest.mark.parametrize("name", ["no-such-set", "..%2F..%2Fetc", "%2Fetc%2Fpasswd"])
def test_an_unknown_dataset_is_a_404(client: TestClient, name: str) -> None:
    assert client.get(f"/datasets/{name}").status_code == 404
    assert client.get(f"/api/datasets/{name}").status_code == 404
