"""Fixtures for the storage tests: stores, hand-built SceneLogs, comparison and tree snapshots."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow.fs as pafs
import pytest

from simsplat_core.types import CameraImage, MapFeature, ObjectInfo, SceneLog, Track
from storage import ArtifactStore
from storage.store import LOCKS_DIR

try:
    from pyarrow._fs import _MockFileSystem  # in-memory filesystem without atomic rename (like S3)
except ImportError:  # pragma: no cover - depends on the pyarrow build
    _MockFileSystem = None


@pytest.fixture
def store(tmp_path: Path) -> ArtifactStore:
    return ArtifactStore(tmp_path / "root")


@pytest.fixture
def mock_store() -> ArtifactStore:
    """A store on an in-memory filesystem that cannot rename atomically (object-store code paths)."""
    if _MockFileSystem is None:
        pytest.skip("pyarrow build has no _MockFileSystem")
    store = ArtifactStore("bucket/prefix", filesystem=_MockFileSystem())
    assert not store.renames_atomically
    return store


def _f32(x: np.ndarray) -> np.ndarray:
    """float64 array whose values are exactly float32-representable."""
    return np.asarray(x, dtype=np.float32).astype(np.float64)


def build_log(
    seq_id: str = "seq0",
    *,
    num_frames: int = 3,
    cameras: tuple[str, ...] = ("front", "left"),
    height: int = 4,
    width: int = 6,
    pixels: bool = True,
    exact: bool = True,
    seed: int = 0,
) -> SceneLog:
    """A small but complete SceneLog exercising every field.

    ``exact``: floats are float32-representable (round trip is bit-exact); otherwise arbitrary float64.
    """
    rng = np.random.default_rng(seed)
    cast = _f32 if exact else (lambda a: np.asarray(a, dtype=np.float64))
    timestamps = 1_700_000_000_000_000 + np.arange(num_frames, dtype=np.int64) * 100_000
    ego = np.repeat(np.eye(4)[None], num_frames, axis=0)
    ego[:, 0, 3] = cast(np.arange(num_frames) * 1.37)
    ego[1:, :3, :3] = cast(np.eye(3) + rng.normal(0, 1e-3, (3, 3)))
    ego[0] = np.eye(4)
    images = []
    for f in range(num_frames):
        for c, cam in enumerate(cameras):
            K = cast(np.array([[500.1 + c, 0, width / 2], [0, 500.2, height / 2], [0, 0, 1]]))
            c2w = cast(ego[f] @ np.diag([1.0, -1.0, -1.0, 1.0]) + rng.normal(0, 1e-2, (4, 4)) * [[1], [1], [1], [0]])
            img = depth = inst = None
            if pixels and not (f == num_frames - 1 and c == len(cameras) - 1):  # last one: no pixels
                img = rng.random((height, width, 3), dtype=np.float32)
                if not (f == 0 and c == 1):  # one image without depth / instance
                    depth = rng.uniform(1, 80, (height, width)).astype(np.float32)
                    depth[0, 0] = np.inf
                    inst = np.zeros((height, width), np.int32)
                    inst[1, :2] = 2**24  # largest exactly-representable id
                    inst[2, 3] = 70_001
            images.append(
                CameraImage(
                    frame_idx=f,
                    timestamp_us=int(timestamps[f]) + c,
                    camera=cam,
                    K=K,
                    cam_to_world=c2w,
                    width=width,
                    height=height,
                    image=img,
                    depth=depth,
                    instance=inst,
                    split="test" if f == num_frames - 1 else "train",
                )
            )
    frames = np.arange(num_frames, dtype=np.int64)
    tracks = (
        Track(
            "veh_1",
            frames,
            cast(rng.normal(10, 5, (num_frames, 3))),
            cast(np.tile([4.5, 1.9, 1.6], (num_frames, 1))),
            cast(rng.uniform(-3, 3, num_frames)),
            cast(rng.uniform(0, 15, num_frames)),
            np.array([True, False, True][:num_frames] + [True] * max(0, num_frames - 3)),
        ),
        Track(
            "ped_2",
            frames[1:],
            cast(rng.normal(0, 3, (num_frames - 1, 3))),
            cast(np.tile([0.6, 0.6, 1.8], (num_frames - 1, 1))),
            cast(rng.uniform(-3, 3, num_frames - 1)),
            cast(rng.uniform(0, 2, num_frames - 1)),
            np.ones(num_frames - 1, bool),
        ),
        Track("cone_3", frames[:0], np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0, bool)),
    )
    objects = (
        ObjectInfo(
            "veh_1", "vehicle", "rigid", 70_001, "a black sedan turning left", {"color": "black", "sub": "sedan"}
        ),
        ObjectInfo("ped_2", "pedestrian", "nonrigid", 2**24, "", {"behavior": "crossing", "note": "äöü ✓"}),
        ObjectInfo("cone_3", "static", "static", 3),
    )
    map_features = (
        MapFeature("lane_0", "lane", cast(rng.normal(0, 50, (5, 3)))),
        MapFeature("cw_1", "crosswalk", cast(rng.normal(0, 50, (4, 3)))),
        MapFeature("edge_2", "road_edge", np.zeros((0, 3))),
    )
    return SceneLog(
        seq_id=seq_id,
        source="synthetic",
        timestamps_us=timestamps,
        ego_poses=ego,
        images=tuple(images),
        tracks=tracks,
        objects=objects,
        map_features=map_features,
        metadata={"seed": str(seed), "city": "nowhere"},
    ).validate()


@pytest.fixture
def make_log() -> Callable[..., SceneLog]:
    return build_log


def _same(a: np.ndarray | None, b: np.ndarray | None, exact: bool) -> bool:
    if a is None or b is None:
        return a is None and b is None
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    if exact or not np.issubdtype(a.dtype, np.floating):
        return bool(np.array_equal(a, b, equal_nan=np.issubdtype(a.dtype, np.floating)))
    return bool(np.allclose(a, b, rtol=1e-6, atol=1e-5, equal_nan=True))


def assert_logs_equal(expected: SceneLog, actual: SceneLog, *, exact: bool = True) -> None:
    """Field-by-field comparison (arrays: dtype, shape, values; bit-exact when ``exact``)."""
    for name in ("seq_id", "source", "metadata", "objects"):
        assert getattr(actual, name) == getattr(expected, name), name
    assert _same(expected.timestamps_us, actual.timestamps_us, True)
    assert _same(expected.ego_poses, actual.ego_poses, exact)
    assert len(actual.images) == len(expected.images)
    for e, a in zip(expected.images, actual.images):
        where = f"{e.camera}/{e.frame_idx}"
        for name in ("frame_idx", "timestamp_us", "camera", "width", "height", "split"):
            assert getattr(a, name) == getattr(e, name), f"{where}: {name}"
        for name in ("K", "cam_to_world", "image", "depth", "instance", "valid_mask"):
            exact_field = exact or name in ("image", "depth", "instance", "valid_mask")
            assert _same(getattr(e, name), getattr(a, name), exact_field), f"{where}: {name}"
    assert [t.object_id for t in actual.tracks] == [t.object_id for t in expected.tracks]
    for e, a in zip(expected.tracks, actual.tracks):
        for name in ("frame_idx", "center", "size", "heading", "speed", "visible"):
            assert _same(np.asarray(getattr(e, name)), getattr(a, name), exact), f"track {e.object_id}: {name}"
    assert [(m.feature_id, m.kind) for m in actual.map_features] == [
        (m.feature_id, m.kind) for m in expected.map_features
    ]
    for e, a in zip(expected.map_features, actual.map_features):
        assert _same(e.points, a.points, exact), f"map feature {e.feature_id}"


@pytest.fixture
def logs_equal() -> Callable[..., None]:
    return assert_logs_equal


def snapshot_tree(root: Path) -> dict[str, str]:
    """``{relative path: sha256}`` of every file under ``root``, hidden ones included; dirs as ``"<dir>"``. The
    commit locks under ``.locks/`` are left out: lock files, kept by design, are not artifacts."""
    result: dict[str, str] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = [d for d in dirnames if d != LOCKS_DIR]
        for d in dirnames:
            result[os.path.relpath(os.path.join(dirpath, d), root)] = "<dir>"
        for f in filenames:
            path = os.path.join(dirpath, f)
            with open(path, "rb") as fh:
                result[os.path.relpath(path, root)] = hashlib.sha256(fh.read()).hexdigest()
    return result


@pytest.fixture
def snapshot() -> Callable[[Path], dict[str, str]]:
    return snapshot_tree


@pytest.fixture
def local_fs() -> pafs.LocalFileSystem:
    return pafs.LocalFileSystem()
