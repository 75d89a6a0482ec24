"""Argoverse 2 sensor-log loader against the public av2-api test log."""

from __future__ import annotations

import collections
import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow.feather as feather
import pytest

from simsplat_core.data import CorruptLogError, load_av2_log
from simsplat_core.data.av2 import RING_CAMERAS, poses_from_columns
from simsplat_core.geometry import invert_transform, transform_points, wrap_angle, yaw_of_rotation
from simsplat_core.types import CATEGORIES, SceneLog

pytestmark = pytest.mark.shared_data

SAMPLE = Path("av2") / "sensor-log-7fab2350"


@pytest.fixture(scope="module")
def log_dir(shared_data: Path) -> Path:
    return shared_data / SAMPLE


@pytest.fixture(scope="module")
def log(log_dir: Path) -> SceneLog:
    return load_av2_log(log_dir)


@pytest.fixture()
def log_copy(log_dir: Path, tmp_path: Path) -> Path:
    """A writable copy of the sample log in ``tmp_path`` (for corrupting)."""
    dst = tmp_path / "log"
    shutil.copytree(log_dir, dst)
    for path in dst.rglob("*"):
        path.chmod(0o755 if path.is_dir() else 0o644)
    return dst


def test_frames_poses_and_tracks(log: SceneLog) -> None:
    assert log.source == "av2" and log.seq_id == "sensor-log-7fab2350"
    assert log.num_frames == 156 and len(log.tracks) == len(log.objects) == 114
    np.testing.assert_array_equal(log.ego_poses[0], np.eye(4))
    assert np.all(np.diff(log.timestamps_us) > 90_000) and np.all(np.diff(log.timestamps_us) < 110_000)
    travelled = np.linalg.norm(log.ego_poses[-1, :3, 3])
    assert 10.0 < travelled < 300.0
    assert sorted(obj.instance_id for obj in log.objects) == list(range(1, 115))
    assert sum(len(tr) for tr in log.tracks) == 11364


def test_categories(log: SceneLog) -> None:
    counts = collections.Counter(obj.category for obj in log.objects)
    assert set(counts) <= set(CATEGORIES)
    assert counts["vehicle"] > 50 and counts["pedestrian"] > 5 and counts["cyclist"] > 0 and counts["static"] > 0
    av2 = {obj.attributes["av2_category"]: obj.category for obj in log.objects}
    assert av2["REGULAR_VEHICLE"] == "vehicle" and av2["BOX_TRUCK"] == "vehicle"
    assert av2["PEDESTRIAN"] == "pedestrian" and av2["BICYCLE"] == "cyclist"
    assert av2["BOLLARD"] == "static" and av2["CONSTRUCTION_CONE"] == "static"
    assert av2["STROLLER"] == "other"
    node_types = {obj.category: obj.node_type for obj in log.objects}
    assert node_types == {
        "vehicle": "rigid",
        "pedestrian": "nonrigid",
        "cyclist": "rigid",
        "static": "static",
        "other": "rigid",
    }


def test_speeds_plausible(log: SceneLog) -> None:
    speeds = np.concatenate([tr.speed for tr in log.tracks])
    assert np.all(np.isfinite(speeds)) and speeds.min() >= 0.0 and speeds.max() < 60.0
    static = [tr for tr, obj in zip(log.tracks, log.objects) if obj.category == "static"]
    assert np.median(np.concatenate([tr.speed for tr in static])) < 0.5
    assert max(tr.speed.max() for tr in log.tracks) > 5.0  # something drives


def test_frame0_and_later_boxes_round_trip_to_raw_annotations(log: SceneLog, log_dir: Path) -> None:
    table = feather.read_table(log_dir / "annotations.feather").to_pydict()
    cols = {k: np.asarray(v) for k, v in table.items()}
    frame_ts = np.unique(cols["timestamp_ns"])
    for frame in (0, 77):
        rows = np.flatnonzero(cols["timestamp_ns"] == frame_ts[frame])
        raw = poses_from_columns({k: cols[k][rows] for k in ("qw", "qx", "qy", "qz", "tx_m", "ty_m", "tz_m")})
        ego_from_world = invert_transform(log.ego_poses[frame])
        for row, raw_pose in zip(rows, raw):
            track = log.track(str(cols["track_uuid"][row]))
            i = track.index_of(frame)
            assert i is not None
            in_ego = transform_points(ego_from_world, track.center[i : i + 1])[0]
            np.testing.assert_allclose(in_ego, raw_pose[:3, 3], atol=1e-6)
            heading_ego = track.heading[i] - yaw_of_rotation(log.ego_poses[frame, :3, :3])
            assert abs(wrap_angle(heading_ego - yaw_of_rotation(raw_pose[:3, :3]))) < 0.02
            np.testing.assert_allclose(
                track.size[i], [cols["length_m"][row], cols["width_m"][row], cols["height_m"][row]]
            )


def test_ring_cameras(log: SceneLog) -> None:
    assert log.cameras == RING_CAMERAS
    assert len(log.images) == 7 * 156 and all(img.image is None for img in log.images)
    front = next(img for img in log.images_at(0) if img.camera == "ring_front_center")
    assert (front.width, front.height) == (1550, 2048)
    np.testing.assert_allclose(front.cam_to_world[:3, 2], [1, 0, 0], atol=0.03)  # looks forward
    np.testing.assert_allclose(front.cam_to_world[:3, 0], [0, -1, 0], atol=0.03)  # image x = ego right
    # Objects ahead of the ego at frame 0 project inside ring_front_center.
    to_cam = invert_transform(front.cam_to_world)
    ahead = 0
    for track in log.tracks:
        i = track.index_of(0)
        if i is None:
            continue
        x, y, _ = track.center[i]
        if 5 < x < 80 and abs(y) < 0.3 * x:
            p = transform_points(to_cam, track.center[i : i + 1])[0]
            u, v = (front.K @ p)[:2] / p[2]
            assert 0 <= u < front.width and 0 <= v < front.height
            assert v > front.K[1, 2] - 0.2 * front.height  # not floating in the sky
            assert track.visible[i] or log.object(track.object_id).attributes["num_interior_pts_max"] == "0"
            ahead += 1
    assert ahead >= 5
    distortion = json.loads(log.metadata["distortion"])
    assert set(distortion) == set(RING_CAMERAS)


def test_map_features(log: SceneLog) -> None:
    kinds = collections.Counter(f.kind for f in log.map_features)
    assert kinds["lane"] == 163 and kinds["crosswalk"] == 11 and kinds["drivable_area"] == 13
    assert kinds["road_edge"] > 0
    assert len({f.feature_id for f in log.map_features}) == len(log.map_features)
    # The ego starts on a lane: the nearest lane centre-line vertex is close, and the map is local.
    lanes = np.concatenate([f.points for f in log.map_features if f.kind == "lane"])
    assert np.min(np.linalg.norm(lanes[:, :2], axis=1)) < 10.0
    assert np.all(np.abs(lanes[:, 2]) < 20.0)  # city heights removed


def test_missing_column(log_copy: Path) -> None:
    path = log_copy / "annotations.feather"
    table = feather.read_table(path)
    feather.write_feather(table.drop_columns(["tx_m"]), path)
    with pytest.raises(CorruptLogError, match=r"annotations\.feather.*column 'tx_m'") as info:
        load_av2_log(log_copy)
    assert info.value.path == str(path)


def test_missing_pose_column(log_copy: Path) -> None:
    path = log_copy / "city_SE3_egovehicle.feather"
    feather.write_feather(feather.read_table(path).drop_columns(["qw"]), path)
    with pytest.raises(CorruptLogError, match=r"city_SE3_egovehicle\.feather.*column 'qw'"):
        load_av2_log(log_copy)


def test_missing_camera_calibration(log_copy: Path) -> None:
    path = log_copy / "calibration" / "intrinsics.feather"
    table = feather.read_table(path)
    feather.write_feather(table.slice(1), path)  # drops ring_front_center
    with pytest.raises(CorruptLogError, match=r"intrinsics\.feather.*sensor_name.*ring_front_center"):
        load_av2_log(log_copy)


def test_truncated_feather(log_copy: Path) -> None:
    path = log_copy / "annotations.feather"
    path.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(CorruptLogError, match=r"annotations\.feather: file: not a readable feather table"):
        load_av2_log(log_copy)


def test_broken_map_json(log_copy: Path) -> None:
    path = log_copy / "map" / "log_map_archive.json"
    path.write_text(path.read_text()[:5000])
    with pytest.raises(CorruptLogError, match=r"log_map_archive\.json: line \d+ column \d+: invalid JSON") as info:
        load_av2_log(log_copy)
    assert info.value.path == str(path)


def test_map_with_missing_field(log_copy: Path) -> None:
    path = log_copy / "map" / "log_map_archive.json"
    doc = json.loads(path.read_text())
    lane_id = sorted(doc["lane_segments"])[0]
    del doc["lane_segments"][lane_id]["right_lane_boundary"]
    path.write_text(json.dumps(doc))
    with pytest.raises(CorruptLogError, match=rf"field 'lane_segments\[{lane_id}\]\.right_lane_boundary'"):
        load_av2_log(log_copy)


def test_missing_map_file(log_copy: Path) -> None:
    (log_copy / "map" / "log_map_archive.json").unlink()
    with pytest.raises(CorruptLogError, match="no log_map_archive"):
        load_av2_log(log_copy)


def test_city_name_from_map_file_name(log_copy: Path) -> None:
    old = log_copy / "map" / "log_map_archive.json"
    old.rename(old.with_name("log_map_archive_7fab2350-0000-0000-0000-000000000000____PIT_city_71.json"))
    loaded = load_av2_log(log_copy, seq_id="renamed")
    assert loaded.seq_id == "renamed"
    assert loaded.metadata["city_name"] == "PIT"
    assert loaded.metadata["log_id"] == "7fab2350-0000-0000-0000-000000000000"
