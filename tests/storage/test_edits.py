"""Stored edits: the edits table, trajectories, the delta (rebuilds the edited graph), atomic edit directories,
failure records."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from simsplat_core.editing.commands import EditProgram, program_from_json
from simsplat_core.editing.delta import apply_delta
from simsplat_core.editing.result import AddedNode, EditDelta
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scene import RigidNode
from simsplat_core.scene.pose_track import Extrapolation, PoseTrack
from simsplat_core.scene.transforms import poses_from_boxes
from storage import ArtifactStore, SchemaError, read_exr, read_exr_header
from storage.edits import (
    DeltaBase,
    EditRecord,
    append_edit_record,
    edit_dir,
    edits_table_relpath,
    list_edits,
    read_edit_delta,
    read_edit_manifest,
    read_edit_program,
    read_edit_records,
    read_trajectories,
    record_failure,
    staged_edit,
    trajectories_table,
)
from tests.simsplat_core.scene.graphs import gaussians, make_graph

PROGRAM = program_from_json(json.dumps({"prompt": "remove the car", "commands": [
    {"op": "remove", "target": {"description": "the car"}}]}))


def _record(edit_id: str = "e1", status: str = "succeeded", reason: str = "") -> EditRecord:
    return EditRecord(run_id="run1", seq_id="unit", edit_id=edit_id, prompt=PROGRAM.prompt,
                      command_json=PROGRAM.model_dump_json(), status=status, failure_reason=reason)


def _track(n: int = 7, start: float = 0.0, step: float = 0.75) -> PoseTrack:
    """A track on its own times, running past the 5-frame axis of ``make_graph``."""
    times = start + step * np.arange(n)
    center = np.stack([10.0 + 2.0 * np.arange(n), np.full(n, -1.0), np.full(n, 0.7)], axis=1)
    poses = torch.as_tensor(poses_from_boxes(center, np.full(n, 0.1)), dtype=torch.float32)
    present = torch.ones(n, dtype=torch.bool)
    present[-1] = False
    return PoseTrack(times, poses, present, Extrapolation.HOLD, Extrapolation.ABSENT)


def _delta() -> EditDelta:
    retrack = _track(5, 0.0, 1.0)  # node 3 (the pedestrian of make_graph) gets a track of its own
    added = AddedNode(node_id=10, object_id="inserted_0", asset_id="veh-red-sedan", category="vehicle",
                      track=_track(), arc_length=np.linspace(0.0, 12.0, 7))
    return EditDelta(removed_node_ids=(1,), added=(added,), retracked={3: retrack})


def _node_for(added: AddedNode) -> RigidNode:
    """Stand-in for ``editing.assets.nodes.asset_node``: a small box of Gaussians."""
    n = len(added.track)
    return RigidNode(added.node_id, gaussians([[0.0, 0.0, 0.0], [1.0, 0.0, 0.2]], (0.9, 0.1, 0.1), seed=7),
                     object_id=added.object_id, category=added.category, scale=2.0,
                     poses=torch.eye(4).repeat(n, 1, 1), present=torch.ones(n, dtype=torch.bool))


def _states(n_steps: int = 5) -> AgentStates:
    t = np.arange(n_steps)
    valid = np.ones((3, n_steps), bool)
    valid[2, :2] = False
    xy = np.stack([np.stack([t * 1.0, t * 0.0], -1), np.stack([5 + t, t * 0.5], -1), np.stack([t * 0.0, -t], -1)])
    return AgentStates(object_ids=("ego", "car", "inserted_0"), categories=("vehicle", "vehicle", "pedestrian"),
                       sources=("log", "edited", "inserted"), node_ids=np.array([-1, 1, 10]), frame_idx=t,
                       times=t / 10.0, xy=xy, z=np.full((3, n_steps), 0.75) + 0.01 * t, heading=np.zeros((3, n_steps)),
                       speed=np.ones((3, n_steps)), size=np.array([[4.5, 1.9, 1.5], [4.0, 1.8, 1.4], [0.5, 0.5, 1.7]]),
                       valid=valid)


def test_edits_table_appends_and_numbers_attempts(tmp_path):
    store = ArtifactStore(str(tmp_path))
    assert read_edit_records(store, "run1") == []
    first = append_edit_record(store, _record("e1", "refused", "not_found: no purple bus in this scene"))
    second = append_edit_record(store, _record("e1"))
    other = append_edit_record(store, _record("e2"))
    assert (first.attempt, second.attempt, other.attempt) == (1, 2, 1)
    rows = read_edit_records(store, "run1")
    assert [(r.edit_id, r.attempt, r.status) for r in rows] == [("e1", 1, "refused"), ("e1", 2, "succeeded"),
                                                                ("e2", 1, "succeeded")]
    assert rows[0].failure_reason.startswith("not_found: ")
    # the parts are the DESIGN table, with its schema name; no temporaries left
    parts = sorted((tmp_path / edits_table_relpath("run1")).iterdir())
    assert len(parts) == 3 and all(store.read_table(str(p.relative_to(tmp_path)), "edits").num_rows == 1 for p in parts)
    assert not [p for p in (tmp_path / "edits" / "run1").rglob("*") if ".tmp-" in p.name]


def test_edit_record_checks_status_and_reason():
    with pytest.raises(ValueError, match="status"):
        _record(status="done")
    with pytest.raises(ValueError, match="failure_reason"):
        _record(status="refused")
    with pytest.raises(ValueError, match="failure_reason"):
        _record(status="succeeded", reason="not_found: x")


def test_trajectories_table_has_every_valid_step_and_round_trips(tmp_path):
    states = _states()
    table = trajectories_table("e1", states)
    assert table.num_rows == int(states.valid.sum())
    assert table.column("object_id").to_pylist().count("inserted_0") == 3
    assert set(table.column("source").to_pylist()) == {"log", "edited", "inserted"}
    store = ArtifactStore(str(tmp_path))
    with staged_edit(store, _record(), key="k1") as writer:
        writer.trajectories("e1", states)
    back = read_trajectories(store, "run1", "unit", "e1")
    assert back.schema.metadata[b"schema_version"] == b"3"
    rows = [r for r in back.to_pylist() if r["object_id"] == "car"]
    assert [r["step"] for r in rows] == [0, 1, 2, 3, 4]
    assert rows[3]["x"] == pytest.approx(8.0) and rows[3]["category"] == "vehicle"
    car = states.index("car")
    assert rows[3]["z"] == pytest.approx(states.z[car, 3])
    assert (rows[3]["length"], rows[3]["width"], rows[3]["height"]) == pytest.approx(tuple(states.size[car]))


def test_version_2_trajectories_read_with_null_box_columns(tmp_path):
    import pyarrow.parquet as pq

    from storage.schemas.edits import TRAJECTORY_BOX_COLUMNS

    table = trajectories_table("e1", _states()).drop_columns(list(TRAJECTORY_BOX_COLUMNS))
    old = table.replace_schema_metadata({b"schema_name": b"trajectories", b"schema_version": b"2"})
    pq.write_table(old, str(tmp_path / "t.parquet"))
    back = ArtifactStore(str(tmp_path)).read_table("t.parquet", "trajectories")
    assert back.num_rows == table.num_rows
    for name in TRAJECTORY_BOX_COLUMNS:
        assert back.column(name).null_count == back.num_rows


def test_delta_round_trip_and_rebuild_equals_applying(tmp_path):
    graph, delta = make_graph(), _delta()
    store = ArtifactStore(str(tmp_path))
    base = DeltaBase("unit", "abc123", "bank9", tuple(int(f) for f in graph.frame_indices))
    with staged_edit(store, _record(), key="k1") as writer:
        writer.command(PROGRAM)
        writer.delta(delta, base)
    stored = read_edit_delta(store, "run1", "unit", "e1")
    assert stored.base == base
    back = stored.delta
    assert back.removed_node_ids == (1,) and sorted(back.retracked) == [3]
    (added,) = back.added
    assert (added.node_id, added.object_id, added.asset_id, added.category) == (10, "inserted_0", "veh-red-sedan",
                                                                                  "vehicle")
    assert np.allclose(added.arc_length, np.linspace(0.0, 12.0, 7))
    assert added.track.after is Extrapolation.ABSENT and added.track.before is Extrapolation.HOLD
    assert np.array_equal(added.track.times, delta.added[0].track.times)
    assert torch.equal(added.track.mask, delta.added[0].track.mask)
    # no Gaussians in the delta: only references and pose tracks
    files = store.walk(edit_dir("run1", "unit", "e1") + "/delta")
    assert files == ["delta.json", "pose_tracks.parquet"]
    applied = apply_delta(graph, delta, _node_for)
    rebuilt = apply_delta(graph, back, _node_for)
    assert [n.node_id for n in rebuilt.nodes] == [n.node_id for n in applied.nodes] == [0, 2, 3, 10]
    assert rebuilt.revision == applied.revision
    for t in (0.0, 1.5, 3.0, 4.0, 6.0):  # 6.0: past the axis, the added node's own track decides
        a, b = applied.at(t), rebuilt.at(t)
        assert a.node_slices == b.node_slices
        assert torch.allclose(a.means, b.means, atol=1e-6)
    assert 10 not in {nid for nid, _, _ in applied.at(6.0).node_slices}  # ABSENT after its track
    assert graph.revision == "" and [n.node_id for n in graph.nodes] == [0, 1, 2, 3]  # the stored graph unchanged


def test_apply_delta_rejects_deltas_of_another_graph():
    graph = make_graph()
    with pytest.raises(ValueError, match=r"removed node\(s\) \[7\]"):
        apply_delta(graph, EditDelta(removed_node_ids=(7,)), _node_for)
    added = dataclasses.replace(_delta().added[0], node_id=2)
    with pytest.raises(ValueError, match="taken"):
        apply_delta(graph, EditDelta(added=(added,)), _node_for)


def test_staged_edit_is_all_or_nothing(tmp_path):
    store = ArtifactStore(str(tmp_path))
    with staged_edit(store, _record(), key="k1", info={"scene_hash": "abc"}) as writer:
        writer.command(PROGRAM)
        rgb = np.random.default_rng(0).random((16, 24, 3)).astype(np.float32)
        writer.render("front", 3, rgb, np.ones((16, 24), np.float32), np.full((16, 24), 12))
        writer.png("bev.png", np.zeros((8, 8, 3), np.uint8))
        writer.validation({"ok": True})
    manifest = read_edit_manifest(store, "run1", "unit", "e1")
    assert manifest is not None and manifest["key"] == "k1" and manifest["scene_hash"] == "abc"
    assert manifest["renders"] == 1 and manifest["bytes"]["total"] == sum(
        v for k, v in manifest["bytes"].items() if k != "total")
    exr = edit_dir("run1", "unit", "e1") + "/renders/front/000003.exr"
    assert read_exr_header(store, exr)["channels"] == ["R", "G", "B", "A", "id"]
    assert np.array_equal(read_exr(store, exr)["id"], np.full((16, 24), 12.0, np.float32))
    before = {p: store.read_bytes(edit_dir("run1", "unit", "e1") + "/" + p)
              for p in store.walk(edit_dir("run1", "unit", "e1"))}

    with pytest.raises(RuntimeError, match="render crashed"), staged_edit(store, _record(), key="k2") as writer:
        writer.command(EditProgram(prompt="other", commands=PROGRAM.commands))
        raise RuntimeError("render crashed")
    after = {p: store.read_bytes(edit_dir("run1", "unit", "e1") + "/" + p)
             for p in store.walk(edit_dir("run1", "unit", "e1"))}
    assert after == before  # the stored edit is untouched
    assert [r.attempt for r in read_edit_records(store, "run1")] == [1]  # no row for the crashed write
    assert list_edits(store, "run1", "unit") == ["e1"]
    assert not [p for p in (tmp_path / "edits" / "run1" / "unit").iterdir() if p.name.startswith(".")]


def test_failure_record_writes_only_the_record(tmp_path):
    store = ArtifactStore(str(tmp_path))
    refused = _record("e9", "refused", "not_found: no purple bus in this scene")
    record_failure(store, refused, PROGRAM)
    assert read_edit_program(store, "run1", "unit", "e9") == PROGRAM
    assert sorted(store.walk(edit_dir("run1", "unit", "e9"))) == ["command.json", "failure.json"]
    assert read_edit_manifest(store, "run1", "unit", "e9") is None  # not a complete edit
    assert list_edits(store, "run1", "unit") == []
    # a prompt that did not parse: the row only
    record_failure(store, dataclasses.replace(refused, edit_id="e10", command_json=""))
    assert not store.exists(edit_dir("run1", "unit", "e10"))
    # a failure never touches a complete edit of the same id
    with staged_edit(store, _record("e1"), key="k1") as writer:
        writer.command(PROGRAM)
    record_failure(store, _record("e1", "failed", "error: RuntimeError: boom"), PROGRAM)
    assert read_edit_manifest(store, "run1", "unit", "e1") is not None
    assert not store.exists(edit_dir("run1", "unit", "e1") + "/failure.json")
    statuses = [(r.edit_id, r.attempt, r.status) for r in read_edit_records(store, "run1")]
    assert statuses == [("e9", 1, "refused"), ("e10", 1, "refused"), ("e1", 1, "succeeded"), ("e1", 2, "failed")]


def test_corrupt_delta_is_named(tmp_path):
    store = ArtifactStore(str(tmp_path))
    with staged_edit(store, _record(), key="k1") as writer:
        writer.delta(_delta(), DeltaBase("unit", "abc", "bank", (0, 1, 2, 3, 4)))
    rel = edit_dir("run1", "unit", "e1") + "/delta/pose_tracks.parquet"
    store.write_bytes(rel, b"garbage")
    with pytest.raises(Exception, match="pose_tracks.parquet"):
        read_edit_delta(store, "run1", "unit", "e1")
    store.write_json(edit_dir("run1", "unit", "e1") + "/delta/delta.json", {"format": "other"})
    with pytest.raises(Exception, match="not an edit delta"):
        read_edit_delta(store, "run1", "unit", "e1")


def test_trajectories_of_an_old_schema_version_are_refused(tmp_path):
    import pyarrow as pa

    from storage.schemas.edits import TRAJECTORIES_SCHEMA

    store = ArtifactStore(str(tmp_path))
    old = TRAJECTORIES_SCHEMA.with_metadata({b"schema_name": b"trajectories", b"schema_version": b"1"})
    table = pa.Table.from_pylist([], schema=old)
    import pyarrow.parquet as pq

    pq.write_table(table, str(tmp_path / "t.parquet"))
    with pytest.raises(SchemaError, match="older than the oldest readable"):
        store.read_table("t.parquet", "trajectories")


def _append_many(root: str, edit_id: str, n: int) -> None:
    store = ArtifactStore(root)
    for _ in range(n):
        append_edit_record(store, _record(edit_id))


def test_concurrent_appends_lose_no_row(tmp_path):
    """Two processes appending at once: the store's lock serialises the read-modify-write. (Fresh interpreters,
    not forks: a fork of the test process inherits its threads and servers.)"""
    import subprocess
    import sys

    repo = str(Path(__file__).resolve().parents[2])
    script = ("import sys; from tests.storage.test_edits import _append_many; "
              "_append_many(sys.argv[1], sys.argv[2], 8)")
    workers = [subprocess.Popen([sys.executable, "-c", script, str(tmp_path), f"e{k}"], cwd=repo,
                                stderr=subprocess.PIPE, text=True) for k in range(2)]
    errors = [w.communicate(timeout=120)[1] for w in workers]
    assert [w.returncode for w in workers] == [0, 0], errors
    rows = read_edit_records(ArtifactStore(str(tmp_path)), "run1")
    assert len(rows) == 16
    for k in range(2):
        assert sorted(r.attempt for r in rows if r.edit_id == f"e{k}") == list(range(1, 9))


def test_trajectory_states_read_back_the_agents_and_fall_back_to_the_log_without_box_columns():
    from storage.edits import trajectory_states

    states = _states()
    log = dataclasses.replace(states.take([0, 1]), sources=("log", "log"), size=np.array([[4.5, 1.9, 1.5],
                                                                                         [3.0, 1.5, 1.2]]))
    back = trajectory_states(trajectories_table("e1", states), log)
    assert back.object_ids == states.object_ids and back.sources == states.sources
    np.testing.assert_array_equal(back.valid, states.valid)
    np.testing.assert_allclose(back.xy[states.valid], states.xy[states.valid], atol=1e-5)
    np.testing.assert_allclose(back.size, states.size, atol=1e-5)
    np.testing.assert_allclose(back.z[states.valid], states.z[states.valid], atol=1e-5)
    older = trajectories_table("e1", states).drop(["z", "length", "width", "height"])
    fallback = trajectory_states(older, log)
    np.testing.assert_allclose(fallback.size[1], [3.0, 1.5, 1.2])  # the log's box of the edited car
    np.testing.assert_allclose(fallback.size[2], [0.6, 0.6, 1.75])  # a pedestrian's box for the inserted one
