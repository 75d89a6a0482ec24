"""Pictures of an edit: the bird's-eye view (paths, colours by change) and the before/after grid."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.types import MapFeature
from simsplat_core.viz.before_after import OUTLINE, FramePair, before_after_picture, pick_views, sample_steps
from simsplat_core.viz.bev import EDITED_COLOR, INSERTED_COLOR, REFINED_COLOR, REMOVED_COLOR, edit_bev
from simsplat_core.viz.bev_animation import bev_animation_frames, bev_fps
from storage.pictures import encode_mp4

T = 20


def _agents(sources: tuple[str, ...], ids: tuple[str, ...], ys: list[float]) -> AgentStates:
    t = np.arange(T)
    n = len(ids)
    xy = np.stack([np.stack([t * 1.0, np.full(T, y)], -1) for y in ys])
    return AgentStates(object_ids=ids, categories=("vehicle",) * n, sources=sources, node_ids=np.arange(n) - 1,
                       frame_idx=t, times=t / 10.0, xy=xy, z=np.full((n, T), 0.8), heading=np.zeros((n, T)),
                       speed=np.full((n, T), 10.0), size=np.tile([4.5, 1.9, 1.6], (n, 1)), valid=np.ones((n, T), bool))


def _has(img: np.ndarray, color: tuple[int, int, int]) -> int:
    return int(np.all(img == np.array(color, np.uint8), axis=-1).sum())


def test_bev_colours_edited_inserted_and_removed_agents():
    road = MapFeature("road", "drivable_area", np.array([[-20, -20, 0], [60, -20, 0], [60, 20, 0], [-20, 20, 0.0]]))
    before = _agents(("log", "log", "log"), ("ego", "car", "van"), [0.0, 6.0, -6.0])
    after = _agents(("log", "edited", "inserted"), ("ego", "car", "new"), [0.0, 3.0, 10.0])
    img = edit_bev([road], before, after, title="test", size=400)
    assert img.shape == (400, 400, 3) and img.dtype == np.uint8
    unchanged = edit_bev([road], before, before, size=400)  # nothing changed: the change colours in the legend only
    for color in (EDITED_COLOR, INSERTED_COLOR, REMOVED_COLOR):
        assert _has(img, color) > _has(unchanged, color) + 20, color


def test_bev_draws_agents_that_reacted_in_their_own_colour():
    before = _agents(("log", "log", "log"), ("ego", "car", "follower"), [0.0, 6.0, 6.0])
    after = _agents(("log", "edited", "refined"), ("ego", "car", "follower"), [0.0, 6.0, 3.0])
    reacted = edit_bev([], before, after, size=400)
    unrefined = edit_bev([], before, _agents(("log", "edited", "log"), ("ego", "car", "follower"), [0.0, 6.0, 3.0]),
                         size=400)
    assert _has(reacted, REFINED_COLOR) > _has(unrefined, REFINED_COLOR) + 20


def test_bev_animation_plays_log_and_refined_side_by_side_as_mp4(tmp_path):
    before = _agents(("log", "log"), ("ego", "car"), [0.0, 6.0])
    after = _agents(("log", "refined"), ("ego", "car"), [0.0, 3.0])
    frames = bev_animation_frames([], before, after, title="brake", size=160, every=2)
    assert len(frames) == T // 2 and frames[0].shape == (160, 320, 3)
    right = frames[3][:, 160:]
    left = frames[3][:, :160]
    assert _has(right, REFINED_COLOR) > 0 and _has(left, REFINED_COLOR) <= _has(edit_bev([], before, before, size=160,
                                                                                           step=6), REFINED_COLOR)
    assert bev_fps(after) == pytest.approx(10.0)
    data = encode_mp4(frames, bev_fps(after))
    assert data[4:8] == b"ftyp"  # an MP4 container
    path = tmp_path / "bev.mp4"
    path.write_bytes(data)
    capture = cv2.VideoCapture(str(path))
    assert int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) == len(frames)
    with pytest.raises(ValueError, match="frame 1"):
        encode_mp4([frames[0], frames[1][:, :100]])


def test_bev_rejects_states_of_other_lengths():
    a = _agents(("log",), ("ego",), [0.0])
    b = AgentStates(**{**a.__dict__, "frame_idx": a.frame_idx[:5], "times": a.times[:5], "xy": a.xy[:, :5],
                       "z": a.z[:, :5], "heading": a.heading[:, :5], "speed": a.speed[:, :5], "valid": a.valid[:, :5]})
    with pytest.raises(ValueError, match="steps"):
        edit_bev([], a, b)


def test_sample_steps_spread_over_the_active_steps():
    active = np.zeros(40, bool)
    active[10:31] = True
    assert sample_steps(active, 4) == [10, 17, 23, 30]
    assert sample_steps(np.zeros(3, bool), 4) == [0, 1, 2]  # nothing active: every step, no repeats
    pixels = np.zeros((10, 3), int)
    pixels[2:8, 1] = 50
    pixels[4, 2] = 80
    assert pick_views(pixels, 3) == [(2, 1), (3, 1), (4, 2)]  # biggest views (ties: earliest)
    approaching = np.zeros((40, 2), int)
    approaching[:, 0] = np.arange(40) * 10  # an inserted car that grows in view
    views = pick_views(approaching, 4)
    assert [row for row, _ in views] == [24, 29, 34, 39]  # the largest views, at least 40 / 8 = 5 frames apart
    assert pick_views(np.full((10, 3), 5), 3) == []  # too few pixels anywhere


def test_before_after_puts_original_above_edited():
    red = np.zeros((16, 24, 3), np.float32)
    red[..., 0] = 1.0
    blue = np.zeros_like(red)
    blue[..., 2] = 1.0
    mask = np.zeros((16, 24), bool)
    mask[4:10, 5:15] = True
    blue8 = (blue * 255).astype(np.uint8)  # uint8 images are taken as they are
    img = before_after_picture([FramePair("f0", red, blue8, None, mask), FramePair("f1", red, blue)], scale=1.0)
    red_rows = np.flatnonzero(np.all(img == (255, 0, 0), axis=-1).any(axis=1))
    blue_rows = np.flatnonzero(np.all(img == (0, 0, 255), axis=-1).any(axis=1))
    assert red_rows.size == 16 and blue_rows.size == 16 and red_rows.max() < blue_rows.min()
    assert _has(img, (255, 0, 0)) == 2 * 16 * 24  # the original row untouched
    outline = np.flatnonzero(np.all(img == OUTLINE, axis=-1).any(axis=1))
    assert outline.size and outline.min() >= blue_rows.min()  # the edited object outlined in the edited row
    with pytest.raises(ValueError, match="differ"):
        before_after_picture([FramePair("f0", red, blue[:8])])
