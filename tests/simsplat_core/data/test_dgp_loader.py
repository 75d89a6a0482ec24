"""DGP (DDAD format) scene loader against TRI's public DGP test scene."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError
from simsplat_core.data.dgp import find_scene_file, lidar_depth, load_dgp_scene, read_lidar_points, sweep_points_world
from simsplat_core.data.dgp_format import parse_scene
from simsplat_core.data.ego_mask import DDAD_EGO_BODY, ego_polygons_from_json, polygon_valid_mask
from simsplat_core.geometry import transform_points
from simsplat_core.types import SceneLog
from tests.simsplat_core.data.dgp_checks import projected_box_ious

pytestmark = pytest.mark.shared_data

SAMPLE = Path("dgp") / "scene_02"
SCALE = 0.25


@pytest.fixture(scope="module")
def scene_dir(shared_data: Path) -> Path:
    return shared_data / SAMPLE


@pytest.fixture(scope="module")
def log(scene_dir: Path) -> SceneLog:
    return load_dgp_scene(scene_dir, image_scale=SCALE)


@pytest.fixture()
def scene_copy(scene_dir: Path, tmp_path: Path) -> Path:
    """A writable copy of the scene's JSON files (for corrupting; images and sweeps are left out)."""
    dst = tmp_path / "scene"
    shutil.copytree(scene_dir, dst, ignore=shutil.ignore_patterns("*.jpg", "*.npz"))
    for path in dst.rglob("*"):
        path.chmod(0o755 if path.is_dir() else 0o644)
    return dst


def test_scene_loads_with_cameras_poses_and_tracks(log: SceneLog) -> None:
    assert log.source == "dgp" and log.num_frames == 3
    assert len(log.images) == 18 and {img.camera for img in log.images} == set(DDAD_EGO_BODY)
    assert np.allclose(log.ego_poses[0], np.eye(4))
    steps = np.linalg.norm(np.diff(log.ego_poses[:, :3, 3], axis=0), axis=1)
    assert np.all((steps > 1.0) & (steps < 1.6))  # about 1.3 m per 1 s step, driving forward (+x)
    assert log.ego_poses[2, 0, 3] > 2.0
    assert len(log.tracks) == 13 and all(len(t.frame_idx) >= 1 for t in log.tracks)
    assert {o.category for o in log.objects} <= {"vehicle", "pedestrian", "cyclist", "other"}
    test_views = [(img.frame_idx, img.camera) for img in log.images if img.split == "test"]
    assert [f for f, _ in test_views] == [0, 1, 2] and len({c for _, c in test_views}) == 3


def test_3d_boxes_project_onto_the_annotated_2d_boxes(scene_dir: Path, log: SceneLog) -> None:
    ious = projected_box_ious(scene_dir, log, SCALE)
    assert len(ious) >= 10
    assert np.median(ious) > 0.6


def test_lidar_depth_agrees_across_frames_with_the_right_pose(scene_dir: Path, log: SceneLog) -> None:
    cam = next(img for img in log.images if img.frame_idx == 0 and img.camera == "CAMERA_01")
    reference = lidar_depth(sweep_points_world(scene_dir, 0), cam.K, cam.cam_to_world, cam.width, cam.height)
    samples = parse_scene(find_scene_file(scene_dir))
    lidar = next(d for d in samples[1].datums if d.kind == "point_cloud")
    sweep = read_lidar_points(scene_dir / lidar.filename)  # lidar frame = ego frame in this rig

    def error(ego_pose: np.ndarray) -> float:
        depth = lidar_depth(transform_points(ego_pose, sweep), cam.K, cam.cam_to_world, cam.width, cam.height)
        both = np.isfinite(depth) & np.isfinite(reference)
        return float(np.median(np.abs(depth[both] - reference[both]) / reference[both]))

    right, wrong = error(log.ego_poses[1]), error(log.ego_poses[0])
    assert np.isnan(reference).mean() > 0.5  # sparse: most pixels have no measurement (nan, never inf)
    assert not np.isinf(reference).any()
    assert right < 0.03 and wrong > 2 * right


def test_every_image_carries_its_sweeps_sparse_depth_off_the_ego_body(scene_dir: Path, log: SceneLog) -> None:
    for img in log.images:
        assert img.depth is not None and img.depth.shape == (img.height, img.width)
        measured = np.isfinite(img.depth)
        assert 0.01 < measured.mean() < 0.9 and not np.isposinf(img.depth).any()  # sparse; no sky claimed
        if img.valid_mask is not None:
            assert not measured[~img.valid_mask].any()  # the ego body is not scenery
    first = log.images[0]
    expected = lidar_depth(sweep_points_world(scene_dir, first.frame_idx), first.K, first.cam_to_world,
                           first.width, first.height)
    assert np.array_equal(np.isfinite(first.depth), np.isfinite(expected) & (
        first.valid_mask if first.valid_mask is not None else True))


def test_side_cameras_mask_the_ego_body(log: SceneLog) -> None:
    for img in log.images:
        if img.camera == "CAMERA_01":
            assert img.valid_mask is None
            continue
        assert img.valid_mask is not None and img.valid_mask.shape == (img.height, img.width)
        assert img.valid_mask[-1].sum() == 0 and img.valid_mask[0].all()  # body at the bottom, scene at the top
        assert 0.05 < 1 - img.valid_mask.mean() < 0.4


def test_user_polygons(tmp_path: Path) -> None:
    path = tmp_path / "ego.json"
    path.write_text(json.dumps({"front": [[[0, 0.5], [1, 0.5], [1, 1], [0, 1]]]}))
    mask = polygon_valid_mask(ego_polygons_from_json(path)["front"], 8, 4)
    assert mask is not None and mask[:2].all() and not mask[3].any()
    path.write_text(json.dumps({"front": [[[0, 0.5], [2, 0.5], [1, 1]]]}))
    with pytest.raises(CorruptLogError, match="ego.json: field 'front'"):
        ego_polygons_from_json(path)


def test_malformed_json_names_file_and_field(scene_copy: Path) -> None:
    scene_file = find_scene_file(scene_copy)
    doc = json.loads(scene_file.read_text())
    del doc["data"][3]["datum"]["image"]["pose"]
    scene_file.write_text(json.dumps(doc))
    with pytest.raises(CorruptLogError, match=r"scene_.*\.json: field 'scene\.data\[3\]\.datum\.image\.pose': missing"):
        load_dgp_scene(scene_copy)
    scene_file.write_text("{not json")
    with pytest.raises(CorruptLogError, match=r"scene_.*\.json: line 1 column 2: not valid JSON"):
        load_dgp_scene(scene_copy)


def test_malformed_calibration_names_file_and_field(scene_copy: Path) -> None:
    cal = next((scene_copy / "calibration").glob("*.json"))
    doc = json.loads(cal.read_text())
    doc["extrinsics"][2]["rotation"]["qw"] = "abc"
    cal.write_text(json.dumps(doc))
    with pytest.raises(CorruptLogError, match=r"field 'calibration\.extrinsics\[2\]\.rotation\.qw': expected a number"):
        load_dgp_scene(scene_copy)
