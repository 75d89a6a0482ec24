"""A corrupt stored artifact (truncated Parquet, an EXR with bytes overwritten, a manifest whose counts or checksums
were edited): reading it raises ``CorruptArtifactError`` naming the file, and the next run of the stage that made it
reports it (a warning naming the file) and recomputes it instead of reusing it."""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Callable
from pathlib import Path

import pytest

from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.scene import ReconstructionConfig
from simsplat_core.world import WorldConfig
from storage import ArtifactStore, CorruptArtifactError, read_exr, read_scene, read_scene_log
from storage.integrity import INTEGRITY_KEY
from storage.markers import MARKER_NAME
from tasks.align import train_motion_aligner
from tasks.logs import generate_synthetic_log
from tasks.reconstruct import StoredScene, reconstruct_scene

SEED = 3
CONFIG = ReconstructionConfig(iterations=4)
WORLD = WorldConfig(num_frames=4, width=64, height=48, test_every=2)


@pytest.fixture(scope="module")
def store(tmp_path_factory: pytest.TempPathFactory) -> ArtifactStore:
    root = str(tmp_path_factory.mktemp("store"))
    generate_synthetic_log.fn(root, SEED, WORLD)
    return ArtifactStore(root)


@pytest.fixture(scope="module")
def seq_id(store: ArtifactStore) -> str:
    (seq,) = store.listdir("logs")
    return seq


def _reconstruct(store: ArtifactStore, seq_id: str) -> StoredScene:
    return reconstruct_scene.fn(store.root, seq_id, CONFIG)


def _truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _overwrite_middle(path: Path) -> None:
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 64] = b"\xff" * 64
    path.write_bytes(bytes(data))


def _edit_manifest(directory: Path, change: Callable[[dict], None]) -> None:
    marker = directory / MARKER_NAME
    manifest = json.loads(marker.read_text())
    change(manifest)
    marker.write_text(json.dumps(manifest))


def _first_render(scene: Path) -> Path:
    return sorted((scene / "renders").rglob("*.exr"))[0]


def _recomputed(store: ArtifactStore, seq_id: str, caplog: pytest.LogCaptureFixture, named: str) -> None:
    """The stage recomputes the scene, warning about ``named``; the new scene reads back."""
    with caplog.at_level(logging.WARNING, logger="storage.integrity"):
        again = _reconstruct(store, seq_id)
    assert not again.skipped
    assert any("will be recomputed" in r.getMessage() and named in r.getMessage() for r in caplog.records)
    assert read_scene(store, seq_id, again.scene_hash).records.gaussians["mean"].shape[0] > 0
    assert _reconstruct(store, seq_id).skipped  # intact again: reused


def test_a_truncated_scene_table_is_named_on_read_and_recomputed(store: ArtifactStore, seq_id: str,
                                                                 caplog: pytest.LogCaptureFixture) -> None:
    scene = Path(store.uri(_reconstruct(store, seq_id).relpath))
    _truncate(scene / "gaussians.parquet")
    with pytest.raises(CorruptArtifactError, match=r"gaussians\.parquet"):
        read_scene(store, seq_id)
    _recomputed(store, seq_id, caplog, "gaussians.parquet")


def test_a_damaged_render_exr_is_named_on_read_and_recomputed(store: ArtifactStore, seq_id: str,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    stored = _reconstruct(store, seq_id)
    render = _first_render(Path(store.uri(stored.relpath)))
    size = render.stat().st_size
    _overwrite_middle(render)
    assert render.stat().st_size == size  # same size: only the checksum can tell
    with pytest.raises(CorruptArtifactError, match=render.name):
        read_exr(store, os.path.relpath(render, store.root))
    _recomputed(store, seq_id, caplog, f"{render.parent.name}/{render.name}: sha256")


@pytest.mark.parametrize("edit", ["rows", "checksum"])
def test_a_manifest_whose_counts_or_checksums_disagree_is_recomputed(store: ArtifactStore, seq_id: str, edit: str,
                                                                     caplog: pytest.LogCaptureFixture) -> None:
    scene = Path(store.uri(_reconstruct(store, seq_id).relpath))

    def change(manifest: dict) -> None:
        if edit == "rows":
            manifest["tables"]["nodes"]["rows"] += 1
        else:
            manifest[INTEGRITY_KEY]["files"]["metrics.parquet"]["sha256"] = "0" * 64

    _edit_manifest(scene, change)
    with pytest.raises(CorruptArtifactError, match=MARKER_NAME):
        read_scene(store, seq_id)
    _recomputed(store, seq_id, caplog, MARKER_NAME)


def test_a_manifest_written_before_checksums_is_checked_by_its_counts(store: ArtifactStore, seq_id: str,
                                                                      caplog: pytest.LogCaptureFixture) -> None:
    scene = Path(store.uri(_reconstruct(store, seq_id).relpath))
    _edit_manifest(scene, lambda manifest: manifest.pop(INTEGRITY_KEY))
    assert _reconstruct(store, seq_id).skipped  # an old, intact scene is still reused
    read_scene(store, seq_id)
    _edit_manifest(scene, lambda manifest: manifest["tables"]["gaussians"].update(rows=1))
    with pytest.raises(CorruptArtifactError, match=r"gaussians\.parquet: \d+ rows, the manifest counts 1"):
        read_scene(store, seq_id)
    _recomputed(store, seq_id, caplog, "gaussians.parquet")


def test_a_truncated_log_table_is_named_on_read_and_regenerated(store: ArtifactStore, seq_id: str,
                                                                caplog: pytest.LogCaptureFixture) -> None:
    _truncate(Path(store.uri(f"logs/{seq_id}/tracks.parquet")))
    with pytest.raises(CorruptArtifactError, match=r"tracks\.parquet"):
        read_scene_log(store, seq_id)
    with caplog.at_level(logging.WARNING, logger="storage.integrity"):
        again = generate_synthetic_log.fn(store.root, SEED, WORLD)
    assert not again.skipped and any("tracks.parquet" in r.getMessage() for r in caplog.records)
    log = read_scene_log(store, seq_id)
    assert log.tracks and log.num_frames == again.summary.num_frames
    assert generate_synthetic_log.fn(store.root, SEED, WORLD).skipped


def test_a_damaged_aligner_model_is_retrained(store: ArtifactStore, seq_id: str,
                                              caplog: pytest.LogCaptureFixture) -> None:
    config = MotionAlignerConfig(epochs=1)
    first = train_motion_aligner.fn(store.root, [seq_id], config)
    (model_file,) = [f for f in store.walk(first.relpath) if f != MARKER_NAME]
    _overwrite_middle(Path(store.uri(f"{first.relpath}/{model_file}")))
    with caplog.at_level(logging.WARNING, logger="storage.integrity"):
        again = train_motion_aligner.fn(store.root, [seq_id], config)
    assert not again.skipped and again.model_hash == first.model_hash
    assert any(f"{model_file}: sha256" in r.getMessage() for r in caplog.records)
    assert train_motion_aligner.fn(store.root, [seq_id], config).skipped
