"""Shape of the generated log: frames, cameras, splits, dtypes, objects, metadata."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simsplat_core.types import CATEGORIES, node_type_for_category, split_for_frame
from simsplat_core.world import WORLD_VERSION, CameraSpec, WorldConfig, default_seq_id, generate_log


def test_default_log_structure(full_logs):
    cfg = WorldConfig()
    for seed, log in full_logs.items():
        assert log.seq_id == default_seq_id(seed) == f"synth-{seed:06d}"
        assert log.source == "synthetic"
        assert log.num_frames == cfg.num_frames
        assert log.cameras == ("front", "front_left", "front_right")
        assert len(log.images) == cfg.num_frames * 3
        np.testing.assert_array_equal(log.ego_poses[0], np.eye(4))
        np.testing.assert_array_equal(np.diff(log.timestamps_us), np.full(cfg.num_frames - 1, 100_000))
        for img in log.images:
            assert img.split == split_for_frame(img.frame_idx, cfg.test_every)
            assert img.image.dtype == np.float32 and img.image.shape == (160, 240, 3)
            assert img.image.min() >= 0.0 and img.image.max() <= 1.0
            assert img.depth.dtype == np.float32 and img.instance.dtype == np.int32
            assert np.all(img.depth > 0)
        assert sum(img.split == "test" for img in log.images) == 3 * (cfg.num_frames // cfg.test_every)
        # metadata: seed, generator version, config summary
        assert log.metadata["seed"] == str(seed)
        assert log.metadata["generator"] == WORLD_VERSION
        assert json.loads(log.metadata["config_json"])["num_frames"] == cfg.num_frames
        assert log.metadata["image_size"] == "240x160"


def test_camera_rig(full_logs):
    log = full_logs[7]
    imgs = {img.camera: img for img in log.images_at(0)}
    fwd = {name: img.cam_to_world[:3, 2] for name, img in imgs.items()}  # optical axes in world
    yaw = {name: np.rad2deg(np.arctan2(v[1], v[0])) for name, v in fwd.items()}
    assert abs(yaw["front"]) < 1.0
    assert 45.0 <= yaw["front_left"] <= 65.0
    assert -65.0 <= yaw["front_right"] <= -45.0
    for img in imgs.values():
        hfov = 2 * np.rad2deg(np.arctan(img.width / 2 / img.K[0, 0]))
        assert 70.0 <= hfov <= 90.0
        assert img.cam_to_world[2, 3] > 1.0  # mounted above the ground


def test_objects_and_counts(full_logs):
    for log in full_logs.values():
        cats = [o.category for o in log.objects]
        assert 8 <= cats.count("vehicle") <= 14
        assert 4 <= cats.count("pedestrian") <= 8
        assert 1 <= cats.count("static") + cats.count("sign") <= 6
        for obj in log.objects:
            assert obj.category in CATEGORIES
            assert obj.node_type == node_type_for_category(obj.category)
            keys = {"subtype", "behavior", "caption_appearance", "caption_motion", "caption_location"}
            assert keys <= set(obj.attributes)
            if obj.category == "pedestrian":
                assert {"upper_color", "lower_color"} <= set(obj.attributes)
            else:
                assert "color" in obj.attributes
            assert obj.caption.startswith(obj.attributes["caption_appearance"])
        visible = [tr.visible.any() for tr in log.tracks]
        assert np.mean(visible) >= 0.75  # most objects appear in some camera
        for tr in log.tracks:
            assert np.allclose(tr.center[:, 2], tr.size[:, 2] / 2)  # boxes stand on the ground
            assert np.all(tr.speed >= 0)


def test_visibility_matches_masks(full_logs):
    log = full_logs[2]
    min_px = WorldConfig().min_visible_pixels
    ids = {o.object_id: o.instance_id for o in log.objects}
    for tr in log.tracks:
        for f in (0, 17, 39):
            px = max(int((img.instance == ids[tr.object_id]).sum()) for img in log.images_at(f))
            assert bool(tr.visible[tr.index_of(f)]) == (px >= min_px)


def test_custom_rig_and_annotation_only():
    cfg = WorldConfig(
        num_frames=5, width=64, height=48, cameras=(CameraSpec("cam0", 0.0, 0.0, 90.0),), render_images=False
    )
    log = generate_log(3, cfg, seq_id="custom")
    assert log.seq_id == "custom" and log.cameras == ("cam0",)
    assert all(img.image is None and img.depth is None for img in log.images)
    assert any(tr.visible.any() for tr in log.tracks)


@pytest.mark.parametrize("kwargs", [{"num_frames": 0}, {"fps": 0.0}, {"cameras": ()}, {"num_vehicles": (5, 2)}])
def test_config_validation(kwargs):
    with pytest.raises(ValueError):
        WorldConfig(**kwargs)
