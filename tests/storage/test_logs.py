"""SceneLog persistence: exact round trip, layout, manifest, skip-on-same-key, atomicity."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import storage.logs
from simsplat_core.types import LogValidationError
from storage import (
    ArtifactStore,
    is_done,
    list_logs,
    read_exr_header,
    read_log_manifest,
    read_marker,
    read_scene_log,
    scene_log_key,
    write_scene_log,
)


def test_round_trip_exact(store: ArtifactStore, make_log, logs_equal) -> None:
    log = make_log()
    written = write_scene_log(store, log, provenance={"producer_key": "abc"})
    assert written.relpath == "logs/seq0" and not written.skipped
    assert written.bytes == sum(store.size(f"logs/seq0/{p}") for p in store.walk("logs/seq0") if p != "_SUCCESS.json")
    assert read_log_manifest(store, "seq0")["provenance"] == {"producer_key": "abc"}
    again = write_scene_log(store, log)
    assert again.skipped and again.bytes == written.bytes and again.key == written.key
    logs_equal(log, read_scene_log(store, "seq0"))


def test_round_trip_float64_is_rounded_once_to_float32(store: ArtifactStore, make_log, logs_equal) -> None:
    log = make_log(exact=False)
    write_scene_log(store, log)
    back = read_scene_log(store, "seq0")
    logs_equal(log, back, exact=False)
    assert back.ego_poses.dtype == np.float64
    assert np.array_equal(back.ego_poses, log.ego_poses.astype(np.float32).astype(np.float64))


def test_layout_and_manifest(store: ArtifactStore, make_log) -> None:
    log = make_log()
    write_scene_log(store, log)
    assert store.listdir("logs/seq0") == [
        "_SUCCESS.json",
        "ego_poses.parquet",
        "frames.parquet",
        "images",
        "map_features.parquet",
        "objects.parquet",
        "tracks.parquet",
    ]
    assert store.listdir("logs/seq0/images") == ["front", "left"]
    assert store.listdir("logs/seq0/images/left") == ["000000.exr", "000001.exr"]  # frame 2: no pixels
    frames = store.read_table("logs/seq0/frames.parquet", "frames")
    uris = frames.column("image_uri").to_pylist()
    assert uris[0] == "images/front/000000.exr" and uris[-1] == ""
    assert read_exr_header(store, "logs/seq0/images/front/000000.exr")["channels"] == ["R", "G", "B", "Z", "id"]
    assert read_exr_header(store, "logs/seq0/images/left/000000.exr")["channels"] == ["R", "G", "B"]
    manifest = read_marker(store, "logs/seq0")
    assert manifest["key"] == scene_log_key(log)
    assert manifest["source"] == "synthetic" and manifest["metadata"] == log.metadata
    assert manifest["tables"]["tracks"]["rows"] == 3 + 2
    assert manifest["tables"]["ego_poses"]["rows"] == 3
    assert manifest["images"]["count"] == 5 and manifest["images"]["bytes"] > 0
    assert all(t["bytes"] > 0 for t in manifest["tables"].values())


def test_load_images_false_and_annotation_only(store: ArtifactStore, make_log, logs_equal) -> None:
    log = make_log()
    write_scene_log(store, log)
    light = read_scene_log(store, "seq0", load_images=False)
    assert all(img.image is None and img.depth is None and img.instance is None for img in light.images)
    assert np.array_equal(light.images[0].K, log.images[0].K)
    annotations = dataclasses.replace(make_log("av2_like"), images=())
    write_scene_log(store, annotations)
    back = read_scene_log(store, "av2_like")
    logs_equal(annotations, back)
    assert back.num_frames == 3 and not store.exists("logs/av2_like/images")


def test_list_logs_only_complete(store: ArtifactStore, make_log) -> None:
    write_scene_log(store, make_log("a"))
    write_scene_log(store, make_log("b", pixels=False))
    store.write_bytes("logs/c/frames.parquet", b"half-written by something else")
    store.write_bytes("logs/.d.tmp-123/frames.parquet", b"temp")
    assert list_logs(store) == ["a", "b"]
    with pytest.raises(FileNotFoundError, match="logs/c"):
        read_scene_log(store, "c")


def test_same_content_skips_and_changed_content_replaces(
    store: ArtifactStore, make_log, snapshot, tmp_path: Path, logs_equal
) -> None:
    log = make_log()
    write_scene_log(store, log)
    before = snapshot(tmp_path)
    write_scene_log(store, make_log())  # equal content: nothing rewritten
    assert snapshot(tmp_path) == before
    changed = dataclasses.replace(log, metadata={**log.metadata, "seed": "1"})
    write_scene_log(store, changed)
    assert is_done(store, "logs/seq0", scene_log_key(changed))
    logs_equal(changed, read_scene_log(store, "seq0"))
    assert store.listdir("logs") == ["seq0"]


def test_failure_mid_write_leaves_store_unchanged(
    store: ArtifactStore, make_log, snapshot, tmp_path: Path, monkeypatch, logs_equal
) -> None:
    old = make_log()
    write_scene_log(store, old)
    before = snapshot(tmp_path)
    calls = {"n": 0}
    real_write_exr = storage.logs.write_exr

    def failing_write_exr(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError("disk full (simulated)")
        return real_write_exr(*args, **kwargs)

    monkeypatch.setattr(storage.logs, "write_exr", failing_write_exr)
    with pytest.raises(OSError, match="simulated"):
        write_scene_log(store, make_log(seed=7))
    assert calls["n"] == 3
    assert snapshot(tmp_path) == before
    logs_equal(old, read_scene_log(store, "seq0"))


def test_invalid_log_writes_nothing(store: ArtifactStore, make_log, snapshot, tmp_path: Path) -> None:
    write_scene_log(store, make_log())
    before = snapshot(tmp_path)
    log = make_log(seed=3)
    bad_image = dataclasses.replace(log.images[1], image=np.zeros((2, 2, 3), np.float32))
    bad = dataclasses.replace(log, images=(log.images[0], bad_image, *log.images[2:]))
    with pytest.raises(LogValidationError, match="image"):
        write_scene_log(store, bad)
    with pytest.raises(ValueError, match="seq_id"):
        write_scene_log(store, dataclasses.replace(log, seq_id="../escape"))
    assert snapshot(tmp_path) == before


def test_round_trip_on_object_store(mock_store: ArtifactStore, make_log, logs_equal) -> None:
    log = make_log()
    write_scene_log(mock_store, log)
    assert list_logs(mock_store) == ["seq0"]
    logs_equal(log, read_scene_log(mock_store, "seq0"))


def test_round_trip_through_file_uri(tmp_path: Path, make_log, logs_equal) -> None:
    uri_store = ArtifactStore(f"file://{tmp_path}/artifacts")
    log = make_log("uri_seq")
    write_scene_log(uri_store, log)
    logs_equal(log, read_scene_log(ArtifactStore(tmp_path / "artifacts"), "uri_seq"))


def test_valid_mask_round_trips_and_keys_only_change_with_a_mask(store: ArtifactStore, make_log, logs_equal) -> None:
    log = make_log()
    key_without = scene_log_key(log)
    first = log.images[0]
    valid = np.ones((first.height, first.width), bool)
    valid[-2:] = False
    masked = dataclasses.replace(log, images=(dataclasses.replace(first, valid_mask=valid), *log.images[1:]))
    assert scene_log_key(masked) != key_without
    assert scene_log_key(dataclasses.replace(log, images=tuple(log.images))) == key_without
    write_scene_log(store, masked)
    back = read_scene_log(store, "seq0")
    logs_equal(masked, back)
    assert np.array_equal(back.images[0].valid_mask, valid) and back.images[1].valid_mask is None
