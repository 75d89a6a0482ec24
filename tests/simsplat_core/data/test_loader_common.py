"""Shared loader helpers: visibility, speeds, track assembly, ids."""

from __future__ import annotations

import numpy as np

from simsplat_core.data.common import BoxObservation, boxes_visible, build_track, finite_difference_speed, safe_seq_id
from simsplat_core.geometry import CV_TO_SENSOR, box_corners, box_corners_batch, make_transform, project_box_bounds
from simsplat_core.types import CameraImage


def _camera(yaw: float) -> CameraImage:
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ CV_TO_SENSOR
    K = np.array([[400.0, 0.0, 320.0], [0.0, 400.0, 240.0], [0.0, 0.0, 1.0]])
    return CameraImage(0, 0, f"cam{yaw:.1f}", K, make_transform(rot, [0.0, 0.0, 1.5]), 640, 480)


def test_box_corners_batch_matches_box_corners() -> None:
    rng = np.random.default_rng(1)
    centers, sizes, headings = rng.normal(size=(6, 3)), rng.uniform(0.5, 5, (6, 3)), rng.uniform(-4, 4, 6)
    expected = np.stack([box_corners(c, s, h) for c, s, h in zip(centers, sizes, headings)])
    np.testing.assert_allclose(box_corners_batch(centers, sizes, headings), expected, atol=1e-12)


def test_boxes_visible_matches_exact_projection() -> None:
    rng = np.random.default_rng(2)
    centers = np.concatenate([rng.uniform(-40, 40, (400, 2)), rng.uniform(0, 2, (400, 1))], axis=1)
    sizes = rng.uniform(0.3, 12.0, (400, 3))
    headings = rng.uniform(-np.pi, np.pi, 400)
    cameras = [_camera(0.0), _camera(2.5)]
    expected = np.array(
        [
            any(
                project_box_bounds(box_corners(c, s, h), cam.K, cam.cam_to_world, 640, 480) is not None
                for cam in cameras
            )
            for c, s, h in zip(centers, sizes, headings)
        ]
    )
    got = boxes_visible(centers, sizes, headings, cameras)
    np.testing.assert_array_equal(got, expected)
    assert 20 < expected.sum() < 380
    assert boxes_visible(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), cameras).shape == (0,)


def test_finite_difference_speed() -> None:
    t = np.array([0.0, 0.1, 0.2, 0.4])
    centers = np.stack([3.0 * t, 4.0 * t, 5.0 * t], axis=1)  # 5 m/s horizontally, z ignored
    np.testing.assert_allclose(finite_difference_speed(t, centers), 5.0)
    assert finite_difference_speed(t[:1], centers[:1]).tolist() == [0.0]


def test_build_track_sorts_and_fills_speed() -> None:
    obs = [
        BoxObservation(2, np.array([2.0, 0, 0]), np.ones(3), 0.0, float("nan"), True),
        BoxObservation(0, np.array([0.0, 0, 0]), np.ones(3), 0.0, 7.0, False),
        BoxObservation(1, np.array([1.0, 0, 0]), np.ones(3), 0.0, float("nan"), True),
    ]
    track = build_track("a", obs, np.array([0, 100_000, 200_000]))
    track.validate()
    assert track.frame_idx.tolist() == [0, 1, 2]
    np.testing.assert_allclose(track.speed, [7.0, 10.0, 10.0])
    assert track.visible.tolist() == [False, True, True]


def test_safe_seq_id() -> None:
    assert safe_seq_id("abc_123-x.y") == "abc_123-x.y"
    assert safe_seq_id("a/b c") == "a_b_c"
    assert safe_seq_id("..") == "log"


def test_loaders_import_without_frameworks() -> None:
    """simsplat_core.data stays framework-free; pyarrow is only imported when AV2 tables are read."""
    import subprocess
    import sys

    code = (
        "import sys, simsplat_core.data; "
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('prefect', 'ray', 'storage', 'pyarrow')); "
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
