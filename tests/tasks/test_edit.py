"""``simsplat edit`` end to end on a small store built here (a 6-frame log without pixels, its initial scene
graph, a ground-truth language scene, a two-asset bank): stored outputs, refusals and bad command files
writing only their failure record, the delta rebuilding the edit, re-runs skipping."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from flows.cli import app
from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, read_exr_header
from storage.edits import (
    edit_dir,
    list_edits,
    read_edit_manifest,
    read_edit_records,
    read_trajectories,
)
from tests.small_store import write_small_store

runner = CliRunner()
SCENE_HASH = "5ce4e0000000000000000000000000000000000000000000000000000000beef"
MODEL_HASH = "a11ce00000000000000000000000000000000000000000000000000000000000"
LANGUAGE_HASH = "1a9000000000000000000000000000000000000000000000000000000000cafe"
FRAMES, CAMERAS = 6, 3


@dataclasses.dataclass(frozen=True)
class Target:
    """A vehicle of the test world whose appearance caption no other object has: ``object_id``, ``words``."""

    object_id: str
    words: str


@pytest.fixture(scope="module")
def world():
    return generate_log(0, WorldConfig(num_frames=FRAMES, width=64, height=48, render_images=False))


@pytest.fixture(scope="module")
def target(world) -> Target:
    captions = [o.attributes.get("caption_appearance", "") for o in world.objects]
    for obj, caption in zip(world.objects, captions):
        if obj.category == "vehicle" and caption and captions.count(caption) == 1:
            return Target(obj.object_id, caption.split(" ", 1)[1])  # "a white sedan" -> "white sedan"
    raise AssertionError("no vehicle with a unique caption in the test world")


@pytest.fixture(scope="module")
def store_root(tmp_path_factory, world) -> str:
    """Seed 0 of the world over 6 frames, 64 x 48 cameras, no pixels."""
    root = tmp_path_factory.mktemp("edit_store")
    write_small_store(str(root), world, scene_hash=SCENE_HASH, model_hash=MODEL_HASH, language_hash=LANGUAGE_HASH)
    return str(root)


def _digest(root: Path, below: str) -> dict[str, str]:
    """Digest of every file under ``root/below`` but the store's commit locks (``.locks/``: lock files, not
    artifacts)."""
    base = root / below
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(base.rglob("*")) if p.is_file() and ".locks" not in p.relative_to(root).parts}


def _edit(store_root: str, *args: str) -> tuple[int, dict]:
    result = runner.invoke(app, ["edit", "--store", store_root, "--seq", "synth-000000", "--json", *args])
    lines = [line for line in result.output.splitlines() if line.startswith("{")]
    assert lines, result.output
    return result.exit_code, json.loads(lines[-1])


def test_edit_stores_every_output_and_leaves_the_scene_alone(store_root, target):
    root = Path(store_root)
    scene_before = _digest(root, "scenes") | _digest(root, "alignment") | _digest(root, "logs")
    code, out = _edit(store_root, "--run-id", "r1", f"remove the {target.words}")
    assert code == 0, out
    assert out["status"] == "succeeded" and out["grounded"][0]["target_object_ids"] == [target.object_id]
    assert out["commands"][0]["op"] == "remove" and out["validation"]["ok"] is True
    store = ArtifactStore(store_root)
    rel = edit_dir("r1", "synth-000000", out["edit_id"])
    files = store.walk(rel)
    renders = [f for f in files if f.startswith("renders/")]
    assert len(renders) == FRAMES * CAMERAS
    for name in ("command.json", "trajectories.parquet", "delta/delta.json", "delta/pose_tracks.parquet",
                 "bev.png", "bev.mp4", "before_after.png", "validation.json", "_SUCCESS.json"):
        assert name in files, name
    reaction = out["refinement"]
    assert reaction["mode"] == "full" and reaction["predictor"] == "reactive"
    assert all(isinstance(why, str) and why for why in reaction["replayed"].values())
    sources = set(read_trajectories(store, "r1", "synth-000000", out["edit_id"]).column("source").to_pylist())
    assert sources <= {"log", "refined"} and ("refined" in sources) == bool(reaction["refined"])
    header = read_exr_header(store, f"{rel}/{renders[0]}")
    assert header["channels"] == ["R", "G", "B", "A", "id"] and header["format"] == ["float", "half"]
    trajectories = read_trajectories(store, "r1", "synth-000000", out["edit_id"])
    assert target.object_id not in set(trajectories.column("object_id").to_pylist())
    assert "ego" in set(trajectories.column("object_id").to_pylist())
    manifest = read_edit_manifest(store, "r1", "synth-000000", out["edit_id"])
    assert manifest["bytes"]["total"] == out["bytes"]["total"] > 0
    assert [(r.status, r.attempt) for r in read_edit_records(store, "r1")] == [("succeeded", 1)]
    after = _digest(root, "scenes") | _digest(root, "alignment") | _digest(root, "logs")
    assert after == scene_before
    # the same edit again is found, not re-rendered
    code, again = _edit(store_root, "--run-id", "r1", f"remove the {target.words}")
    assert code == 0 and again["skipped"] is True and again["edit_id"] == out["edit_id"]
    assert len(read_edit_records(store, "r1")) == 1


def test_no_refine_keeps_everyone_else_on_the_log(store_root, target):
    code, out = _edit(store_root, "--run-id", "r4", f"remove the {target.words}", "--no-refine")
    assert code == 0, out
    assert out["refinement"] is None
    store = ArtifactStore(store_root)
    sources = set(read_trajectories(store, "r4", "synth-000000", out["edit_id"]).column("source").to_pylist())
    assert sources == {"log"}
    bad = runner.invoke(app, ["edit", "--store", store_root, "--seq", "synth-000000", "--predictor", "psychic",
                              f"remove the {target.words}"])
    assert bad.exit_code == 2 and "psychic" in bad.output


def test_a_refused_edit_writes_only_its_failure_record(store_root):
    root = Path(store_root)
    before = _digest(root, ".")
    code, out = _edit(store_root, "--run-id", "r2", "remove the purple bus")
    assert code == 1
    assert out["status"] == "refused" and out["reason"] == "not_found" and "purple bus" in out["message"]
    assert out["edit_dir"] is None
    store = ArtifactStore(store_root)
    (record,) = read_edit_records(store, "r2")
    assert record.status == "refused" and record.failure_reason.startswith("not_found: ")
    assert list_edits(store, "r2", "synth-000000") == []
    changed = {k for k, v in _digest(root, ".").items() if before.get(k) != v}
    assert changed and all(k.startswith("edits/r2/") for k in changed)
    assert not any("/renders/" in k or k.endswith("_SUCCESS.json") for k in changed)


def test_a_malformed_command_file_is_a_schema_error_naming_the_field(store_root, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"commands": [{"op": "remove", "target": {"description": "the van"}},
                                            {"op": "insert", "asset": {"description": "a cone", "count": 99}}]}))
    code, out = _edit(store_root, "--run-id", "r3", "--commands", str(bad))
    assert code == 2
    assert out["status"] == "refused" and out["reason"] == "invalid_command"
    assert "commands.1.asset.count" in out["message"] and str(bad) in out["message"]
    (record,) = read_edit_records(ArtifactStore(store_root), "r3")
    assert record.failure_reason.startswith("invalid_command: ") and record.command_json == ""
    assert not (Path(store_root) / "edits" / "r3" / "synth-000000").exists()
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    code, out = _edit(store_root, "--run-id", "r3", "--commands", str(broken))
    assert code == 2 and "not valid JSON" in out["message"]


def test_the_stored_delta_rebuilds_the_edited_graph(store_root, target):
    from tasks.edit import run_edit
    from tasks.stored_edits import rebuild_edit

    commands = json.dumps({"commands": [
        {"op": "insert", "asset": {"description": "orange traffic cones", "count": 2},
         "placement": {"relation": "in_lane", "distance_m": 12}},
        {"op": "replace", "target": {"object_id": target.object_id}, "asset": {"description": "a yellow sedan"}}]})
    run = run_edit(store_root, "synth-000000", "cones and a yellow car", commands_json=commands, run_id="r4")
    assert run.status == "succeeded", run.message
    assert run.edited is not None and len(run.edited.delta.added) == 3
    rebuilt = rebuild_edit(ArtifactStore(store_root), "r4", "synth-000000", run.edit_id)
    assert rebuilt.revision == run.edited.graph.revision
    for t in range(FRAMES):
        a, b = run.edited.graph.at(float(t)), rebuilt.at(float(t))
        assert a.node_slices == b.node_slices and torch.allclose(a.means, b.means)
    delta_files = ArtifactStore(store_root).walk(f"{edit_dir('r4', 'synth-000000', run.edit_id)}/delta")
    assert delta_files == ["delta.json", "pose_tracks.parquet"]  # references, no Gaussians
    table = read_trajectories(ArtifactStore(store_root), "r4", "synth-000000", run.edit_id)
    sources = dict(zip(table.column("object_id").to_pylist(), table.column("source").to_pylist()))
    assert sources[target.object_id] == "edited" and sources["inserted_00"] == "inserted" and sources["ego"] == "log"
    assert np.isin(["inserted_00", "inserted_01"], table.column("object_id").to_pylist()).all()
