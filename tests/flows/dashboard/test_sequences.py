"""The sequence pages without a browser: the list and one log's page with their JSON twins, the query box answered in
memory (its pictures served, nothing written to the store), a log without camera images, and broken artifacts shown
as messages in the sections they affect while the rest of the page still renders."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from simsplat_core.eval.grounding.gt_scene import language_scene_from_log
from simsplat_core.language.text import default_text_encoder
from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, write_scene_log
from storage.language_scenes import list_language_scenes, write_language_scene
from storage.scenes import list_scenes
from tests.flows.dashboard.store_fixture import DashboardStore

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def _png(client: TestClient, aid: str) -> bytes:
    response = client.get(f"/files/{aid}")
    assert response.status_code == 200 and response.headers["content-type"] == "image/png", aid
    assert response.content.startswith(PNG)
    return response.content


def test_the_list_shows_every_log_with_what_it_has(client: TestClient, dashboard_store: DashboardStore) -> None:
    rows = client.get("/api/sequences").json()["rows"]
    assert rows["error"] == ""
    (row,) = [r["value"] for r in rows["value"]]
    assert row["seq_id"] == dashboard_store.seq_id and row["source"] == "synthetic"
    assert row["frames"] == 6 and row["cameras"] == ["front", "front_left", "front_right"] and row["images"] == 18
    assert row["scenes"] == 1 and row["aligned"] is True and row["objects"] > 0
    page = client.get("/sequences")
    assert page.status_code == 200 and f'href="/sequences/{dashboard_store.seq_id}"' in page.text


def test_the_sequence_page_shows_its_pictures_and_quality(client: TestClient, dashboard_store: DashboardStore) -> None:
    view = client.get(f"/api/sequences/{dashboard_store.seq_id}").json()
    assert view["has_images"] is True and view["answer"] is None
    for name in ("facts", "bev", "contact_sheet", "reconstruction", "objects"):
        assert view[name]["error"] == "", (name, view[name]["error"])
    sheet = view["contact_sheet"]["value"]
    assert sheet["frames"][0] == 0 and sheet["frames"][-1] == 5 and len(sheet["rows"]) == len(sheet["frames"])
    assert all(len(row) == 3 for row in sheet["rows"])
    _png(client, sheet["rows"][0][0]["picture"])
    _png(client, view["bev"]["value"])
    quality = view["reconstruction"]["value"]
    assert quality["scene_hash"] == list_scenes(ArtifactStore(dashboard_store.root), dashboard_store.seq_id)[-1]
    (compared,) = quality["comparisons"]  # the test scene stored no test render: one is rendered for the page
    assert compared["rendered_now"] is True and compared["ground_truth"] != compared["render"]
    assert _png(client, compared["ground_truth"]) != _png(client, compared["render"])
    objects = view["objects"]["value"]["objects"]
    assert {o["category"] for o in objects} >= {"vehicle", "pedestrian"}
    assert any(o["caption"] and o["motion"] and o["location"] for o in objects)
    page = client.get(f"/sequences/{dashboard_store.seq_id}")
    assert page.status_code == 200 and "Contact sheet" in page.text and 'class="problem"' not in page.text


def test_the_query_box_grounds_a_description_in_memory(client: TestClient, dashboard_store: DashboardStore) -> None:
    objects = client.get(f"/api/sequences/{dashboard_store.seq_id}").json()["objects"]["value"]["objects"]
    captions = [o["caption"] for o in objects if o["category"] == "vehicle"]
    target = next(o for o in objects if o["category"] == "vehicle" and captions.count(o["caption"]) == 1)
    answer = client.get(f"/api/sequences/{dashboard_store.seq_id}", params={"q": f"the {target['caption'][2:]}"}
                        ).json()["answer"]
    assert answer["error"] == ""
    result = answer["value"]
    assert [m["object_id"] for m in result["matches"]] == [target["object_id"]]
    assert result["ranking"][0]["chosen"] is True and result["frame"] in range(6)
    _png(client, result["picture"])
    _png(client, result["bev"])
    page = client.get(f"/sequences/{dashboard_store.seq_id}", params={"q": f"the {target['caption'][2:]}"})
    assert 'class="answer"' in page.text and target["object_id"] in page.text
    root = Path(dashboard_store.root)
    assert not (root / "queries").exists() and not (root / "searches").exists()  # read only


def test_an_unknown_sequence_is_not_found(client: TestClient) -> None:
    assert client.get("/api/sequences/synth-999999").status_code == 404
    page = client.get("/sequences/synth-999999")
    assert page.status_code == 404 and "synth-999999" in page.text
    assert client.get("/sequences/.hidden").status_code == 404


@pytest.fixture(scope="module")
def imageless_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, str]:
    """A store holding one log without camera images, aligned from its tracks (no node-id maps)."""
    store = ArtifactStore(str(tmp_path_factory.mktemp("imageless")))
    log = generate_log(1, WorldConfig(num_frames=6, render_images=False))
    write_scene_log(store, log)
    scene = language_scene_from_log(log, default_text_encoder(), appearance="ground_truth")
    write_language_scene(store, "ab" * 32, "cd" * 32, scene, None)
    assert list_language_scenes(store, log.seq_id)
    return store.root, log.seq_id


def test_a_log_without_images_has_no_sheet_but_answers_queries(imageless_store: tuple[str, str]) -> None:
    root, seq_id = imageless_store
    client = TestClient(create_app(DashboardSettings(root)))
    (row,) = client.get("/api/sequences").json()["rows"]["value"]
    assert row["value"]["images"] == 0 and row["value"]["scenes"] == 0
    view = client.get(f"/api/sequences/{seq_id}", params={"q": "all pedestrians"}).json()
    assert view["has_images"] is False and view["contact_sheet"] is None and view["reconstruction"] is None
    assert view["bev"]["error"] == "" and view["objects"]["error"] == ""
    result = view["answer"]["value"]
    assert result["matches"] and {m["category"] for m in result["matches"]} == {"pedestrian"}
    assert result["picture"] == "" and result["frame"] is None  # no cameras: the bird's-eye view answers
    _png(client, result["bev"])
    page = client.get(f"/sequences/{seq_id}", params={"q": "all pedestrians"})
    assert page.status_code == 200 and "Contact sheet" not in page.text and 'class="problem"' not in page.text


def _broken_copy(dashboard_store: DashboardStore, tmp_path: Path, *, garbage: str) -> TestClient:
    """A copy of the dashboard store with the file matching ``garbage`` (a glob under the root) overwritten."""
    root = tmp_path / "store"
    shutil.copytree(dashboard_store.root, root)
    (victim,) = root.glob(garbage)
    victim.write_bytes(b"not a parquet file")
    return TestClient(create_app(DashboardSettings(str(root))))


def test_corrupt_metrics_show_in_the_quality_section_only(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    client = _broken_copy(dashboard_store, tmp_path, garbage="scenes/*/*/metrics.parquet")
    view = client.get(f"/api/sequences/{dashboard_store.seq_id}").json()
    assert "metrics.parquet" in view["reconstruction"]["error"]
    assert view["contact_sheet"]["error"] == "" and view["objects"]["error"] == "" and view["bev"]["error"] == ""
    page = client.get(f"/sequences/{dashboard_store.seq_id}")
    assert page.status_code == 200 and page.text.count('class="problem"') == 1


def test_a_corrupt_language_scene_shows_in_objects_and_query(dashboard_store: DashboardStore, tmp_path: Path) -> None:
    client = _broken_copy(dashboard_store, tmp_path, garbage="alignment/*/scenes/*/*/node_language.parquet")
    view = client.get(f"/api/sequences/{dashboard_store.seq_id}", params={"q": "a red car"}).json()
    assert "node_language.parquet" in view["objects"]["error"]
    assert "node_language.parquet" in view["answer"]["error"]
    assert view["contact_sheet"]["error"] == "" and view["reconstruction"]["error"] == ""


def test_a_corrupt_log_table_is_named_and_the_list_still_renders(dashboard_store: DashboardStore,
                                                                 tmp_path: Path) -> None:
    client = _broken_copy(dashboard_store, tmp_path, garbage="logs/*/tracks.parquet")
    assert client.get("/api/sequences").json()["rows"]["value"][0]["error"] == ""  # the list reads manifests only
    view = client.get(f"/api/sequences/{dashboard_store.seq_id}").json()
    assert "tracks.parquet" in view["facts"]["error"] and "tracks.parquet" in view["bev"]["error"]
    page = client.get(f"/sequences/{dashboard_store.seq_id}")
    assert page.status_code == 200 and "tracks.parquet" in page.text
