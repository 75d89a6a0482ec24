"""Reconstructed scene persistence: exact round trip, layout, errors naming file and column, atomicity."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

import storage.scenes
from simsplat_core.scene import SceneRecords
from storage import ArtifactStore, SchemaError
from storage.scenes import (
    list_scenes,
    read_scene,
    read_scene_manifest,
    read_scene_render,
    resolve_scene_hash,
    scene_exists,
    write_scene,
)

HASH_A = "a" * 64
HASH_B = "b" * 64
METRICS = {"psnr_test": 21.5, "ssim_test": 0.71, "iterations": 30.0, "num_gaussians": 7.0}


@dataclasses.dataclass(frozen=True)
class _Render:
    frame_idx: int
    camera: str
    rgb: np.ndarray
    alpha: np.ndarray
    depth: np.ndarray
    node_id: np.ndarray


def make_records(seed: int = 0, scene_id: str = "seq0/aaaaaaaaaaaaaaaa"):
    """A small scene: background node 0, rigid node 3, non-rigid node 7 deformed at frames 1, 2.

    Float values are float32-representable, so the round trip is exact.
    """
    rng = np.random.default_rng(seed)
    n, frames = 7, np.array([0, 1, 2], np.int64)
    node_id = np.array([0, 0, 0, 3, 3, 7, 7], np.int32)
    gaussians = {
        "node_id": node_id,
        "mean": rng.normal(size=(n, 3)).astype(np.float32),
        "log_scale": rng.normal(-2, 0.5, (n, 3)).astype(np.float32),
        "quat": rng.normal(size=(n, 4)).astype(np.float32),
        "color": rng.random((n, 3), dtype=np.float32),
        "opacity_logit": rng.normal(size=n).astype(np.float32),
    }
    nodes = [
        {"node_id": 0, "node_type": "background", "object_id": "", "category": "", "scale": 61.25,
         "center": [1.5, -2.25, 0.125]},
        {"node_id": 3, "node_type": "rigid", "object_id": "veh_1", "category": "vehicle", "scale": 2.5},
        {"node_id": 7, "node_type": "nonrigid", "object_id": "ped_2", "category": "pedestrian", "scale": 0.96875},
    ]
    pose_nodes = np.repeat(np.array([3, 7], np.int32), len(frames))
    node_poses = {
        "node_id": pose_nodes,
        "frame_idx": np.tile(frames, 2),
        "transform": rng.normal(size=(len(pose_nodes), 16)).astype(np.float32),
    }
    deformations = {7: rng.normal(0, 0.01, (len(frames) - 1, 2, 3)).astype(np.float32)}
    return SceneRecords(
        scene_id=scene_id,
        frame_indices=frames,
        gaussians=gaussians,
        nodes=nodes,
        node_poses=node_poses,
        deformations=deformations,
        deformation_frames={7: frames[1:]},
        metadata={"seq_id": "seq0", "init": "depth"},
    ).validate()


def make_renders(height: int = 4, width: int = 5) -> list[_Render]:
    rng = np.random.default_rng(1)
    out = []
    for camera in ("front", "left"):
        depth = rng.uniform(1, 50, (height, width)).astype(np.float32)
        depth[0, 0] = np.inf
        node = np.zeros((height, width), np.int32)
        node[1, 1:3] = 7
        out.append(_Render(9, camera, rng.random((height, width, 3), dtype=np.float32),
                           rng.random((height, width), dtype=np.float32), depth, node))
    return out


def assert_records_equal(expected, actual) -> None:
    assert actual.scene_id == expected.scene_id and actual.metadata == expected.metadata
    assert actual.frame_indices.dtype == np.int64 and np.array_equal(actual.frame_indices, expected.frame_indices)
    assert set(actual.gaussians) == set(expected.gaussians)
    for name, column in expected.gaussians.items():
        got = actual.gaussians[name]
        assert got.dtype == column.dtype and np.array_equal(got, column), f"gaussians.{name}"
    assert actual.nodes == expected.nodes
    for name, column in expected.node_poses.items():
        got = actual.node_poses[name]
        assert got.dtype == column.dtype and np.array_equal(got, column), f"node_poses.{name}"
    assert set(actual.deformations) == set(expected.deformations)
    for node_id, offsets in expected.deformations.items():
        got = actual.deformations[node_id]
        assert got.dtype == np.float32 and np.array_equal(got, offsets), f"deformations[{node_id}]"
        frames = actual.deformation_frames[node_id]
        assert frames.dtype == np.int64 and np.array_equal(frames, expected.deformation_frames[node_id])


def test_round_trip_exact(store: ArtifactStore) -> None:
    records, renders = make_records(), make_renders()
    written = write_scene(store, "seq0", HASH_A, records, METRICS, renders, provenance={"config": {"iterations": 30}})
    assert written.relpath == f"scenes/seq0/{HASH_A}" and not written.skipped
    files = store.walk(written.relpath)
    assert written.bytes == sum(store.size(f"{written.relpath}/{f}") for f in files if f != "_SUCCESS.json")

    loaded = read_scene(store, "seq0")
    assert loaded.scene_hash == HASH_A and loaded.metrics == METRICS
    assert loaded.manifest["provenance"] == {"config": {"iterations": 30}}
    assert_records_equal(records, loaded.records)
    for r in renders:
        channels = read_scene_render(store, "seq0", HASH_A, r.camera, r.frame_idx)
        assert list(channels) == ["R", "G", "B", "A", "Z", "id"]
        assert np.array_equal(np.stack([channels[c] for c in "RGB"], -1), r.rgb)
        assert np.array_equal(channels["A"], r.alpha) and np.array_equal(channels["Z"], r.depth)
        assert np.array_equal(channels["id"].astype(np.int32), r.node_id)

    again = write_scene(store, "seq0", HASH_A, records, METRICS, renders)
    assert again.skipped and again.bytes == written.bytes


def test_layout_tables_and_manifest(store: ArtifactStore) -> None:
    write_scene(store, "seq0", HASH_A, make_records(), METRICS, make_renders(), feature_dim=16)
    rel = f"scenes/seq0/{HASH_A}"
    assert store.listdir(rel) == [
        "_SUCCESS.json",
        "deform",
        "gaussians.parquet",
        "metrics.parquet",
        "node_poses.parquet",
        "nodes.parquet",
        "renders",
    ]
    assert store.walk(f"{rel}/renders") == ["front/000009.exr", "left/000009.exr"]
    poses = store.read_table(f"{rel}/node_poses.parquet", "node_poses")
    assert set(zip(poses.column("node_id").to_pylist(), poses.column("deform_uri").to_pylist())) == {
        (3, ""), (7, "deform/7.parquet"),
    }
    nodes = store.read_table(f"{rel}/nodes.parquet", "nodes")
    assert nodes.schema.field("f_app").type.list_size == 16
    assert not np.any(np.asarray(nodes.column("f_loc").combine_chunks().flatten()))
    metrics = store.read_table(f"{rel}/metrics.parquet", "metrics").to_pylist()
    assert {(m["stage"], m["name"], m["unit"]) for m in metrics} >= {("reconstruct", "psnr_test", "dB")}
    assert {m["run_id"] for m in metrics} == {HASH_A} and {m["seq_id"] for m in metrics} == {"seq0"}
    manifest = read_scene_manifest(store, "seq0", HASH_A)
    assert manifest["key"] == HASH_A and manifest["frame_indices"] == [0, 1, 2]
    assert manifest["tables"]["gaussians"]["rows"] == 7 and manifest["renders"]["count"] == 2
    assert manifest["deformations"] == {"count": 1, "bytes": store.size(f"{rel}/deform/7.parquet"), "nodes": [7]}
    assert manifest["metrics"] == METRICS


def test_latest_complete_scene_prefix_and_missing(store: ArtifactStore) -> None:
    with pytest.raises(FileNotFoundError, match=r"scenes/seq0: no complete reconstructed scene"):
        read_scene(store, "seq0")
    write_scene(store, "seq0", HASH_A, make_records(), METRICS)
    write_scene(store, "seq0", HASH_B, make_records(seed=1), {"psnr_test": 30.0})
    store.write_bytes(f"scenes/seq0/{'c' * 64}/gaussians.parquet", b"half a scene, no marker")
    assert list_scenes(store, "seq0") == [HASH_A, HASH_B]
    assert read_scene(store, "seq0").scene_hash == HASH_B
    assert read_scene(store, "seq0", "aaaaaaaa").scene_hash == HASH_A
    assert resolve_scene_hash(store, "seq0", HASH_B) == HASH_B
    with pytest.raises(FileNotFoundError, match=rf"scenes/seq0/{'c' * 64}: no complete scene"):
        read_scene(store, "seq0", "c" * 64)
    with pytest.raises(ValueError, match="hex"):
        read_scene(store, "seq0", "../x")


def test_missing_column_error_names_file_and_column(store: ArtifactStore, tmp_path: Path) -> None:
    write_scene(store, "seq0", HASH_A, make_records(), METRICS)
    path = tmp_path / "root" / "scenes" / "seq0" / HASH_A / "gaussians.parquet"
    table = pq.read_table(path)
    pq.write_table(table.drop_columns(["opacity_logit"]), path)
    with pytest.raises(SchemaError, match=r"gaussians\.parquet.*column 'opacity_logit' is missing"):
        read_scene(store, "seq0")


def test_missing_deformation_file_is_named(store: ArtifactStore) -> None:
    write_scene(store, "seq0", HASH_A, make_records(), METRICS)
    store.delete(f"scenes/seq0/{HASH_A}/deform/7.parquet")
    with pytest.raises(FileNotFoundError, match=r"deform/7\.parquet"):
        read_scene(store, "seq0")


def test_interrupted_write_leaves_no_visible_scene(store: ArtifactStore, monkeypatch, snapshot, tmp_path: Path) -> None:
    write_scene(store, "seq0", HASH_A, make_records(), METRICS)
    before = snapshot(tmp_path)
    real_write_exr = storage.scenes.write_exr
    calls = {"n": 0}

    def failing_write_exr(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise OSError("disk full (simulated)")
        return real_write_exr(*args, **kwargs)

    monkeypatch.setattr(storage.scenes, "write_exr", failing_write_exr)
    with pytest.raises(OSError, match="simulated"):
        write_scene(store, "seq0", HASH_B, make_records(seed=2), METRICS, make_renders())
    assert calls["n"] == 2
    assert snapshot(tmp_path) == before
    assert list_scenes(store, "seq0") == [HASH_A] and not scene_exists(store, "seq0", HASH_B)
    assert read_scene(store, "seq0").scene_hash == HASH_A


def test_inconsistent_records_write_nothing(store: ArtifactStore, snapshot, tmp_path: Path) -> None:
    records = make_records()
    bad = dataclasses.replace(records, gaussians={**records.gaussians, "mean": records.gaussians["mean"][:3]})
    with pytest.raises(ValueError, match=r"gaussians\['mean'\]: 3 rows, expected 7"):
        write_scene(store, "seq0", HASH_A, bad, METRICS)
    bad = dataclasses.replace(records, deformations={7: np.zeros((3, 2, 3), np.float32)})
    with pytest.raises(ValueError, match=r"deformations\[7\]"):
        write_scene(store, "seq0", HASH_A, bad, METRICS)
    assert not (tmp_path / "root" / "scenes").exists() or not any((tmp_path / "root" / "scenes").rglob("*.parquet"))


def test_round_trip_on_object_store(mock_store: ArtifactStore) -> None:
    records = make_records()
    write_scene(mock_store, "seq0", HASH_A, records, METRICS, make_renders())
    assert list_scenes(mock_store, "seq0") == [HASH_A]
    assert_records_equal(records, read_scene(mock_store, "seq0").records)
