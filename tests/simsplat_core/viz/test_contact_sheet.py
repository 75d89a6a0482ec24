"""Looking at a log: 3D boxes projected into a camera, the ego-frame bird's-eye view, the map, the tiled sheet.

The camera sits 0.8 m above the world origin looking along world +x (OpenCV axes: x right = world -y, y down =
world -z), focal length 100 px, principal point (120, 80) of a 240 x 160 image.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pytest

from simsplat_core.types import CameraImage, MapFeature, ObjectInfo, SceneLog, Track
from simsplat_core.viz.contact_sheet import (
    CATEGORY_COLORS,
    HIGHLIGHT_COLOR,
    MAP_COLORS,
    bev_panel,
    camera_panel,
    contact_sheet,
    draw_map,
)
from tests.simsplat_core.viz.scenes import assert_tinted

W, H, F = 240, 160, 2
K = np.array([[100.0, 0.0, 120.0], [0.0, 100.0, 80.0], [0.0, 0.0, 1.0]])
CAM_TO_WORLD = np.array([[0.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.8], [0.0, 0.0, 0.0, 1.0]])


def _camera(name: str, frame: int = 0, image: np.ndarray | None = None) -> CameraImage:
    return CameraImage(frame, frame * 100_000, name, K, CAM_TO_WORLD, W, H, image)


def _log(objects: Sequence[tuple[str, str, tuple[float, float, float]]] = (), *, ego_poses: np.ndarray | None = None,
         images: tuple[CameraImage, ...] | None = None) -> SceneLog:
    """Standing objects ``(id, category, centre)`` of size 4 x 2 x 1.6 m heading +x, present in every frame."""
    tracks = tuple(Track(oid, np.arange(F), np.tile(center, (F, 1)), np.tile([4.0, 2.0, 1.6], (F, 1)), np.zeros(F),
                         np.zeros(F), np.ones(F, bool)) for oid, _, center in objects)
    infos = tuple(ObjectInfo(oid, category, "rigid", k + 1) for k, (oid, category, _) in enumerate(objects))
    return SceneLog("sheetlog", "synthetic", np.arange(F, dtype=np.int64) * 100_000,
                    np.tile(np.eye(4), (F, 1, 1)) if ego_poses is None else ego_poses,
                    (_camera("front"),) if images is None else images, tracks, infos)


def _diff(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, cols)`` of the pixels that differ."""
    rows, cols = np.nonzero(np.any(a != b, axis=-1))
    return rows, cols


def test_a_box_ahead_is_drawn_where_it_projects() -> None:
    """A 4 x 2 x 1.6 m car 10 m ahead, on the ground: its near face (x = 8 m) spans u 107.5..132.5 and
    v 70..90; its label sits above it."""
    empty = camera_panel(_log(), _camera("front"))
    drawn = camera_panel(_log([("car", "vehicle", (10.0, 0.0, 0.8))]), _camera("front"))
    assert drawn.shape == (H, W, 3) and drawn.dtype == np.uint8
    rows, cols = _diff(drawn, empty)
    assert cols.min() == pytest.approx(107.5, abs=1.5) and cols.max() == pytest.approx(132.5, abs=1.5)
    assert rows.max() == pytest.approx(90, abs=1.5) and rows.min() > 50  # the label above the box, not higher
    bottom = drawn[90, 110:130].astype(float)  # the near face's lower edge
    assert_tinted(bottom[np.argmax(np.abs(bottom - 48).sum(axis=1))], CATEGORY_COLORS["vehicle"], 48)


def test_a_box_behind_the_camera_is_not_drawn() -> None:
    empty = camera_panel(_log(), _camera("front"))
    behind = camera_panel(_log([("car", "vehicle", (-10.0, 0.0, 0.8))]), _camera("front"))
    np.testing.assert_array_equal(behind, empty)


def test_a_box_straddling_the_camera_plane_is_clipped_not_lost() -> None:
    empty = camera_panel(_log(), _camera("front"))
    beside = camera_panel(_log([("car", "vehicle", (0.5, -3.0, 0.8))]), _camera("front"))  # half in front
    rows, cols = _diff(beside, empty)
    assert cols.size and cols.max() == W - 1  # its front half runs off the right of the image


def test_pixels_are_used_and_scaled_with_the_boxes() -> None:
    blue = np.zeros((H, W, 3), np.float32)
    blue[..., 2] = 1.0
    log = _log([("car", "vehicle", (10.0, 0.0, 0.8))], images=(_camera("front", image=blue),))
    full = camera_panel(log, log.images[0])
    half = camera_panel(log, log.images[0], scale=0.5)
    assert tuple(full[H - 1, W // 2]) == (0, 0, 255)  # the camera's own pixels under the drawing
    assert half.shape == (H // 2, W // 2, 3)
    rows, cols = _diff(half, camera_panel(_log(images=(_camera("front", image=blue),)), log.images[0], scale=0.5))
    assert cols.min() == pytest.approx(107.5 / 2, abs=1.5) and rows.max() == pytest.approx(45, abs=1.5)


def test_bev_panel_is_in_the_ego_frame_of_the_frame() -> None:
    """At frame 1 the ego stands at (5, 0) facing world +y; a car at world (5, 10) is 10 m straight ahead: 40 px
    above the centre of a 480 px, 60 m panel."""
    turn = np.eye(4)
    turn[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    turn[:2, 3] = (5.0, 0.0)
    poses = np.stack([np.eye(4), turn])
    with_car = bev_panel(_log([("car", "pedestrian", (5.0, 10.0, 0.8))], ego_poses=poses), 1)
    without = bev_panel(_log(ego_poses=poses), 1)
    rows, cols = _diff(with_car, without)
    assert (rows.min() + rows.max()) / 2 == pytest.approx(240 - 40, abs=1)
    assert (cols.min() + cols.max()) / 2 == pytest.approx(240, abs=1)
    # the car heads world +x: to the ego's right, so it lies across the picture (16 px wide, 8 px tall)
    assert cols.max() - cols.min() == pytest.approx(16, abs=3) and rows.max() - rows.min() == pytest.approx(8, abs=3)
    assert tuple(with_car[240, 240]) == (255, 255, 0)  # the ego, filled at the centre
    side = with_car[200, cols.min():cols.min() + 3].astype(float)
    assert_tinted(side[np.argmax(np.abs(side - 20).sum(axis=1))], CATEGORY_COLORS["pedestrian"], 20)


def test_bev_highlights_objects_and_their_paths() -> None:
    log = _log([("car", "vehicle", (20.0, 0.0, 0.8))])
    moving = Track("car", np.arange(F), np.array([[10.0, -8.0, 0.8], [20.0, 8.0, 0.8]]),
                   np.tile([4.0, 2.0, 1.6], (F, 1)), np.zeros(F), np.zeros(F), np.ones(F, bool))
    log = SceneLog(log.seq_id, log.source, log.timestamps_us, log.ego_poses, log.images, (moving,), log.objects)
    plain = bev_panel(log, 1, extent_m=40.0)
    marked = bev_panel(log, 1, extent_m=40.0, highlight=("car",), window=(0, 1))
    rows, cols = _diff(marked, plain)
    # the path from (10, -8) to (20, 8): pixels (240 + 48, 240 - 60) to (240 - 48, 240 - 120) at 6 px per metre
    assert rows.max() >= 240 - 60 - 2 and cols.max() >= 240 + 48 - 2
    mid = marked[240 - 90, 240].astype(float)  # half way along the path
    assert_tinted(mid, HIGHLIGHT_COLOR, 20)


def test_map_areas_filled_in_drawing_order_and_lines_on_top() -> None:
    canvas = np.zeros((100, 100, 3), np.uint8)
    features = [MapFeature("cw", "crosswalk", np.array([[40.0, 40, 0], [60, 40, 0], [60, 60, 0], [40, 60, 0]])),
                MapFeature("road", "drivable_area", np.array([[0.0, 0, 0], [100, 0, 0], [100, 100, 0], [0, 100, 0]])),
                MapFeature("lane", "lane", np.array([[10.0, 20, 0], [90, 20, 0]])),
                MapFeature("dot", "road_edge", np.array([[5.0, 5, 0]]))]  # a single point: nothing to draw
    draw_map(canvas, features, lambda p: np.round(p[:, :2]).astype(np.int32))
    assert tuple(canvas[50, 50]) == MAP_COLORS["crosswalk"]  # listed first, drawn over the road
    assert tuple(canvas[10, 10]) == MAP_COLORS["drivable_area"]
    assert_tinted(canvas[20, 50], MAP_COLORS["lane"], MAP_COLORS["drivable_area"][0])  # anti-aliased, over the road


def test_contact_sheet_tiles_cameras_then_the_bev() -> None:
    log = _log([("car", "vehicle", (10.0, 0.0, 0.8))], images=(_camera("front"), _camera("front_left"),
                                                                _camera("front", 1)))
    sheet = contact_sheet(log, 0, panel_width=120, columns=2)
    # frame 0: two 120 x 80 camera panels and a 120 x 120 BEV, 2 wide: two rows of 120 px cells
    assert sheet.shape == (240, 240, 3) and sheet.dtype == np.uint8
    np.testing.assert_array_equal(sheet[:80, :120], camera_panel(log, log.images[0], scale=0.5))
    np.testing.assert_array_equal(sheet[:80, 120:], camera_panel(log, log.images[1], scale=0.5))
    assert not sheet[80:120].any()  # camera cells padded below
    np.testing.assert_array_equal(sheet[120:, :120], bev_panel(log, 0, size=120))
    assert not sheet[120:, 120:].any()  # the empty cell
    with pytest.raises(ValueError, match=r"sheetlog: frame 2 outside \[0, 2\)"):
        contact_sheet(log, F)
    assert contact_sheet(_log(images=()), 1, panel_width=100).shape == (100, 300, 3)  # no cameras: the BEV alone
