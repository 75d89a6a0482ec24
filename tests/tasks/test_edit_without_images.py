"""Editing a log without camera images: the public Waymo Open Motion scenario ingested, aligned from its tracks and
map, then edited by prompt through the task function and the CLI (the graph of its tracks, box-only inserts, no
renders), rebuilt from its delta, and a refused prompt. Skipped when ../shared/data is absent; no Prefect start."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from flows.cli import app
from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.scene.track_graph import is_track_graph
from storage import ArtifactStore
from storage.edits import read_edit_delta, read_edit_manifest, read_trajectories
from tasks.align import align_scene, train_motion_aligner
from tasks.edit import run_edit
from tasks.logs import ingest_real_log
from tasks.stored_edits import load_edit_context, rebuild_edit

SAMPLE = "waymo/motion_data_one_scenario.tfrecord"
RUN = "t"


@pytest.fixture(scope="module")
def motion_store(shared_data, tmp_path_factory):
    """The Waymo motion sample ingested into a fresh store, an aligner trained on it, its language scene, and its
    edit context (loaded once)."""
    root = str(tmp_path_factory.mktemp("motion-store"))
    stored = ingest_real_log.fn(root, "waymo-scenario", str(shared_data / SAMPLE))
    seq = stored.relpath.split("/")[1]
    model = train_motion_aligner.fn(root, [seq], MotionAlignerConfig(epochs=20))
    align_scene.fn(root, seq, None, model.model_hash)
    return ArtifactStore(root), seq, load_edit_context(root, seq)


def _rows(store: ArtifactStore, seq: str, edit_id: str, object_id: str) -> list[dict]:
    table = read_trajectories(store, RUN, seq, edit_id).to_pylist()
    return sorted((r for r in table if r["object_id"] == object_id), key=lambda r: r["step"])


@pytest.mark.shared_data
def test_the_lead_vehicle_brakes_to_a_stop_and_the_traffic_is_refined(motion_store) -> None:
    store, seq, loaded = motion_store
    assert not loaded.renders and is_track_graph(loaded.ctx.graph) and loaded.log_key
    run = run_edit(store.root, seq, "the lead vehicle brakes hard", run_id=RUN, loaded=loaded)
    assert run.status == "succeeded", run.message
    (lead,) = run.edited.outcomes[0].changed_object_ids
    rows = _rows(store, seq, run.edit_id, lead)
    assert {r["source"] for r in rows} == {"edited"}
    speeds = np.array([r["speed"] for r in rows])
    assert speeds.max() > 3.0 and speeds[-1] < 0.3  # it was moving and stands at the end
    assert all(r["length"] > 2.0 and r["height"] > 0.5 and r["z"] is not None for r in rows)
    sources = {r["source"] for r in read_trajectories(store, RUN, seq, run.edit_id).to_pylist()}
    assert {"log", "edited", "refined"} <= sources

    files = set(store.listdir(run.edit_uri.removeprefix(store.root).strip("/")))
    assert {"command.json", "trajectories.parquet", "delta", "validation.json", "bev.png", "bev.mp4"} <= files
    assert not files & {"renders", "before_after.png"}
    manifest = read_edit_manifest(store, RUN, seq, run.edit_id)
    assert manifest is not None and manifest["scene_hash"] == "" and manifest["log_key"] == loaded.log_key
    base = read_edit_delta(store, RUN, seq, run.edit_id).base
    assert base.from_log and base.log_key == loaded.log_key

    rebuilt = rebuild_edit(store, RUN, seq, run.edit_id)
    node = next(n for n in rebuilt.object_nodes if n.object_id == lead)
    assert node.track is not None and len(node.gaussians) == 0


@pytest.mark.shared_data
def test_cli_inserts_a_stopped_truck_as_a_box(motion_store) -> None:
    store, seq, _ = motion_store
    result = CliRunner().invoke(app, ["edit", "--store", store.root, "--seq", seq, "--run-id", RUN, "--json",
                                      "insert a stopped truck in the ego lane 30 m ahead"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output.strip().splitlines()[-1])
    edit_id = data["edit_id"]
    (added,) = read_edit_delta(store, RUN, seq, edit_id).delta.added
    assert added.asset_id.startswith("box.truck")
    rows = _rows(store, seq, edit_id, added.object_id)
    assert rows and {r["source"] for r in rows} == {"inserted"}
    xy = np.array([(r["x"], r["y"]) for r in rows])
    assert np.abs(xy - xy[0]).max() < 0.05 and max(abs(r["speed"]) for r in rows) < 0.05  # it stands
    assert rows[0]["length"] > 6.0  # a truck's box
    node = next(n for n in rebuild_edit(store, RUN, seq, edit_id).object_nodes if n.object_id == added.object_id)
    assert len(node.gaussians) == 0 and node.category == "vehicle"


@pytest.mark.shared_data
def test_a_prompt_about_looks_is_refused_with_a_clear_message(motion_store) -> None:
    store, seq, loaded = motion_store
    run = run_edit(store.root, seq, "make the red car stop", run_id=RUN, loaded=loaded)
    assert run.status == "refused" and run.reason == "not_found"
    assert "no camera images" in run.message and "red" in run.message


@pytest.mark.shared_data
def test_cli_mining_needs_no_asset_bank_and_judges_from_the_bev_and_trajectories(motion_store) -> None:
    store, seq, _ = motion_store
    result = CliRunner().invoke(app, ["mine", "--store", store.root, "--seq", seq, "--per-sequence", "1",
                                      "--max-attempts", "1", "--run-id", "mine", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output.strip().splitlines()[-1])
    assert data["totals"]["accepted"] == 1
    (scenario,) = data["scenarios"]
    files = set(store.listdir(scenario["edit_dir"].removeprefix(store.root).strip("/")))
    assert {"trajectories.parquet", "bev.png", "validation.json"} <= files and "renders" not in files


@pytest.mark.shared_data
def test_edits_exported_as_womd_reingest_with_the_edit_and_the_reactions(motion_store, tmp_path) -> None:
    """The two edits above (found again, not re-run) exported as WOMD shards and ingested back: the braking lead
    stands at the end, the truck stands where it was put, and some other agent's path differs from its log."""
    from simsplat_core.data.waymo_scenario import load_waymo_scenario
    from storage import read_scene_log
    from tasks.export import ExportConfig, export_dataset
    from tasks.export_inputs import ExportFilters

    store, seq, loaded = motion_store
    brake = run_edit(store.root, seq, "the lead vehicle brakes hard", run_id=RUN, loaded=loaded)
    truck = run_edit(store.root, seq, "insert a stopped truck in the ego lane 30 m ahead", run_id=RUN, loaded=loaded)
    assert brake.edited is not None and brake.edited.validation.ok  # late arrivals react too: nothing hits it
    config = ExportConfig(name="edited", formats=("womd",), filters=ExportFilters(include="all-edits", runs=(RUN,)),
                          splits=(("train", 1.0),))
    result = export_dataset(store.root, str(tmp_path), config)
    assert result.written == 2 and not result.left_out
    manifest = json.loads((tmp_path / "edited" / "manifest.json").read_text())
    original = {t.object_id: t for t in read_scene_log(store, seq, load_images=False).tracks}
    (shard,) = result.shards  # both scenarios in one shard: one record each
    backs = {}
    for record in range(2):
        back = load_waymo_scenario(tmp_path / "edited" / shard.path, record_index=record)
        backs[back.metadata["scenario_id"]] = back
    brake_id = next(s for s in backs if brake.edit_id[:12] in s)
    (lead,) = brake.edited.outcomes[0].changed_object_ids
    lead_id = str(manifest["scenarios"][brake_id]["track_ids"][lead])
    tracks = {t.object_id: t for t in backs[brake_id].tracks}
    assert tracks[lead_id].speed[-1] < 0.3 < tracks[lead_id].speed.max()
    moved = [o for o, t in original.items()
             if o != lead and o in manifest["scenarios"][brake_id]["track_ids"]
             and len(t) == len(tracks[str(manifest["scenarios"][brake_id]["track_ids"][o])])
             and np.abs(tracks[str(manifest["scenarios"][brake_id]["track_ids"][o])].center - t.center).max() > 0.5]
    assert moved  # the traffic reacted: some agent's path left its log
    assert json.loads(backs[brake_id].metadata["objects_of_interest"]) == [int(lead_id)]
    truck_id = next(s for s in backs if truck.edit_id[:12] in s)
    ids = manifest["scenarios"][truck_id]["track_ids"]
    (added,) = [o for o in ids if o not in original and o != "ego"]
    stands = {t.object_id: t for t in backs[truck_id].tracks}[str(ids[added])]
    assert np.abs(stands.center - stands.center[0]).max() < 0.05 and stands.size[0, 0] > 6.0
