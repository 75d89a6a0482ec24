"""Waymo ``Frame`` TFRecord loader against the public one-frame sample."""

from __future__ import annotations

import collections
import json
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError, load_waymo_frames
from simsplat_core.data.protowire import Field, MessageSchema, decode_message
from simsplat_core.data.tfrecord import encode_tfrecord, iter_tfrecords
from simsplat_core.data.waymo_proto import CAMERA_NAMES, LABEL, parse_frame
from simsplat_core.geometry import box_corners, invert_transform, project_box_bounds, transform_points
from simsplat_core.types import SceneLog

pytestmark = pytest.mark.shared_data

SAMPLE = Path("waymo") / "pvps_data_one_frame.tfrecord"
SIZES = {
    "front": (1920, 1280),
    "front_left": (1920, 1280),
    "front_right": (1920, 1280),
    "side_left": (1920, 886),
    "side_right": (1920, 886),
}


@pytest.fixture(scope="module")
def sample_path(shared_data: Path) -> Path:
    return shared_data / SAMPLE


@pytest.fixture(scope="module")
def log(sample_path: Path) -> SceneLog:
    return load_waymo_frames(sample_path)


def _projected_lidar_labels(path: Path) -> dict[str, list[dict]]:
    """Waymo's own 2D projections of the laser labels (``Frame.projected_lidar_labels``, field 9)."""
    camera_labels = MessageSchema(
        "CameraLabels", (Field(1, "name", "enum"), Field(2, "labels", "message", repeated=True, message=LABEL))
    )
    frame = MessageSchema("Frame", (Field(9, "projected", "message", repeated=True, message=camera_labels),))
    msg = decode_message(next(iter_tfrecords(path)).data, frame)
    return {CAMERA_NAMES[c["name"]]: c["labels"] for c in msg["projected"]}


def _iou(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    return inter / ((a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter)


def test_cameras_and_images(log: SceneLog) -> None:
    assert log.source == "waymo" and log.num_frames == 1
    assert log.seq_id == "1024360143612057520_3580_000_3600_000"
    assert log.cameras == tuple(SIZES)
    np.testing.assert_allclose(log.ego_poses[0], np.eye(4))
    for cam in log.images:
        assert (cam.width, cam.height) == SIZES[cam.camera]
        assert cam.image is not None and cam.image.dtype == np.float32
        assert cam.image.shape == (cam.height, cam.width, 3)
        assert float(cam.image.min()) >= 0.0 and float(cam.image.max()) <= 1.0 and cam.image.std() > 0.05
        fx, fy, cx, cy = cam.K[0, 0], cam.K[1, 1], cam.K[0, 2], cam.K[1, 2]
        assert 1900 < fx < 2200 and abs(fx - fy) < 1.0
        assert abs(cx - cam.width / 2) < 0.1 * cam.width and abs(cy - cam.height / 2) < 0.25 * cam.height
        rot = cam.cam_to_world[:3, :3]
        np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-6)
        assert 1.0 < cam.cam_to_world[2, 3] < 3.0  # mounted on the roof
    front = next(c for c in log.images if c.camera == "front")
    np.testing.assert_allclose(front.cam_to_world[:3, 2], [1, 0, 0], atol=0.02)  # optical axis = forward
    np.testing.assert_allclose(front.cam_to_world[:3, 1], [0, 0, -1], atol=0.02)  # image down = world down
    side_left = next(c for c in log.images if c.camera == "side_left")
    np.testing.assert_allclose(side_left.cam_to_world[:3, 2], [0, 1, 0], atol=0.05)


def test_objects_and_tracks(log: SceneLog) -> None:
    assert len(log.objects) == len(log.tracks) == 75
    counts = collections.Counter(obj.category for obj in log.objects)
    assert counts == {"vehicle": 37, "sign": 25, "pedestrian": 12, "cyclist": 1}
    assert [obj.instance_id for obj in log.objects] == list(range(1, 76))
    assert all(obj.object_id for obj in log.objects)
    types = {obj.category: obj.attributes["waymo_type"] for obj in log.objects}
    assert types["vehicle"] == "TYPE_VEHICLE" and types["sign"] == "TYPE_SIGN"
    assert {obj.node_type for obj in log.objects if obj.category == "pedestrian"} == {"nonrigid"}
    assert all(int(obj.attributes["num_lidar_points_max"]) >= 0 for obj in log.objects)
    speeds = np.concatenate([tr.speed for tr in log.tracks])
    assert np.all(np.isfinite(speeds)) and speeds.max() < 60.0
    visible = np.array([tr.visible[0] for tr in log.tracks])
    assert 10 < visible.sum() < 75  # some labels are behind / outside every camera


def test_metadata(log: SceneLog, sample_path: Path) -> None:
    assert log.metadata["source_file"] == str(sample_path)
    assert log.metadata["context_name"] == log.seq_id
    distortion = json.loads(log.metadata["distortion"])
    assert set(distortion) == set(SIZES)
    assert set(distortion["front"]) == {"k1", "k2", "p1", "p2", "k3"}


def test_boxes_project_where_waymo_projects_them(log: SceneLog, sample_path: Path) -> None:
    """Our K / cam_to_world reproduce Waymo's own 2D projections of the 3D labels."""
    projected = _projected_lidar_labels(sample_path)
    assert set(projected) == set(SIZES)
    for cam in log.images:
        ious = []
        for label in projected[cam.camera]:
            object_id = label["id"].removesuffix("_" + cam.camera.upper())
            track = log.track(object_id)
            box = label["box"]
            ref = (
                box["center_x"] - box["length"] / 2,
                box["center_y"] - box["width"] / 2,
                box["center_x"] + box["length"] / 2,
                box["center_y"] + box["width"] / 2,
            )
            corners = box_corners(track.center[0], track.size[0], track.heading[0])
            mine = project_box_bounds(corners, cam.K, cam.cam_to_world, cam.width, cam.height)
            ious.append(0.0 if mine is None else _iou(ref, mine))
            if mine is not None and log.object(object_id).attributes["num_lidar_points_max"] != "0":
                assert track.visible[0], object_id  # visible = in a camera and hit by lidar
        assert np.median(ious) > 0.95, (cam.camera, ious)
        assert np.mean(np.array(ious) > 0.7) >= 0.9, (cam.camera, ious)


def test_vehicle_ahead_projects_into_front_image(log: SceneLog) -> None:
    front = next(c for c in log.images if c.camera == "front")
    to_cam = invert_transform(front.cam_to_world)
    ahead = 0
    for track, obj in zip(log.tracks, log.objects):
        x, y, _ = track.center[0]
        if obj.category != "vehicle" or not (5 < x < 60 and abs(y) < 0.35 * x):
            continue
        ahead += 1
        cam_pt = transform_points(to_cam, track.center[:1])[0]
        u, v = (front.K @ cam_pt)[:2] / cam_pt[2]
        assert cam_pt[2] > 0 and 0 <= u < front.width and 0 <= v < front.height, obj.object_id
    assert ahead >= 3


def test_image_scale(sample_path: Path, log: SceneLog) -> None:
    half = load_waymo_frames(sample_path, image_scale=0.5, seq_id="half")
    assert half.seq_id == "half"
    for small, full in zip(half.images, log.images):
        assert (small.width, small.height) == (full.width // 2, full.height // 2)
        assert small.image.shape == (small.height, small.width, 3)
        np.testing.assert_allclose(small.K[:2, :2], full.K[:2, :2] / 2)
        # The same world point lands at half the pixel coordinate (pixel-centre convention).
        point = transform_points(full.cam_to_world, np.array([[0.5, -0.3, 20.0]]))
        uv_full = (full.K @ np.array([0.5, -0.3, 20.0]))[:2] / 20.0
        cam_pt = transform_points(invert_transform(small.cam_to_world), point)[0]
        uv_small = (small.K @ cam_pt)[:2] / cam_pt[2]
        np.testing.assert_allclose(uv_small, (uv_full + 0.5) / 2 - 0.5, atol=1e-6)
    with pytest.raises(ValueError, match="image_scale"):
        load_waymo_frames(sample_path, image_scale=0.0)


def _with_timestamp(data: bytes, timestamp_us: int) -> bytes:
    """Append ``timestamp_micros`` (field 2, varint): the last occurrence of a scalar wins."""
    value, out = timestamp_us, bytearray([2 << 3])
    while value >= 0x80:
        out.append(value & 0x7F | 0x80)
        value >>= 7
    out.append(value)
    return data + bytes(out)


def test_multi_record_file_is_sorted_into_frames(sample_path: Path, tmp_path: Path) -> None:
    data = next(iter_tfrecords(sample_path)).data
    t0 = parse_frame(data).timestamp_us
    path = tmp_path / "two.tfrecord"
    path.write_bytes(encode_tfrecord(_with_timestamp(data, t0 + 100_000)) + encode_tfrecord(data))
    two = load_waymo_frames(path, image_scale=0.125)
    assert two.num_frames == 2 and list(two.timestamps_us) == [t0, t0 + 100_000]
    assert len(two.images) == 10 and {img.frame_idx for img in two.images} == {0, 1}
    assert len(two.tracks) == 75 and all(len(tr) == 2 for tr in two.tracks)
    np.testing.assert_allclose(two.ego_poses[1], np.eye(4), atol=1e-9)
    path.write_bytes(encode_tfrecord(data) * 2)
    with pytest.raises(CorruptLogError, match="record 1.*duplicate timestamp"):
        load_waymo_frames(path, image_scale=0.125)


def test_malformed_proto_with_valid_crc(sample_path: Path, tmp_path: Path) -> None:
    data = next(iter_tfrecords(sample_path)).data
    path = tmp_path / "cut_proto.tfrecord"
    path.write_bytes(encode_tfrecord(data[: len(data) // 2]))
    with pytest.raises(CorruptLogError, match=r"record 0 .*field 'Frame\.") as info:
        load_waymo_frames(path)
    assert info.value.record_index == 0 and str(path) in str(info.value)


def test_undecodable_jpeg_names_the_image_field(sample_path: Path, tmp_path: Path) -> None:
    data = next(iter_tfrecords(sample_path)).data
    jpeg = parse_frame(data).images[2].jpeg
    start = data.find(jpeg)
    broken = data[:start] + bytes(len(jpeg)) + data[start + len(jpeg) :]
    path = tmp_path / "bad_jpeg.tfrecord"
    path.write_bytes(encode_tfrecord(broken))
    with pytest.raises(CorruptLogError, match=r"record 0, field 'Frame\.images\[2\]\.image'"):
        load_waymo_frames(path)
