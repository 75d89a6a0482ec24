"""Before / after pictures: frame sampling, view picking, layout and sizes."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.viz.before_after import (
    GAP,
    LABEL_H,
    OUTLINE,
    FramePair,
    before_after_picture,
    pick_views,
    sample_steps,
)


def test_sample_steps_spans_the_active_steps() -> None:
    active = np.zeros(30, bool)
    active[[3, 4, 5, 20, 21]] = True
    assert sample_steps(active, 10) == [3, 4, 5, 20, 21]  # fewer active steps than asked: all of them
    assert sample_steps(active, 2) == [3, 21]  # first and last
    assert sample_steps(active, 1) == [3]
    assert sample_steps(np.zeros(0, bool), 4) == []
    picks = sample_steps(np.ones(101, bool), 5)
    assert picks == [0, 25, 50, 75, 100]  # evenly spread


def test_pick_views_prefers_big_views_spread_over_time_in_the_busiest_camera() -> None:
    pixels = np.zeros((20, 3), int)
    pixels[5] = (10, 400, 50)
    pixels[6] = (0, 0, 390)  # big, but right next to frame 5
    pixels[15] = (200, 0, 0)
    pixels[0] = (0, 29, 0)  # below min_pixels
    assert pick_views(pixels, 2) == [(5, 1), (15, 0)]  # frames at least 20 / 4 = 5 apart, in time order
    assert pick_views(pixels, 3) == [(5, 1), (15, 0)]  # nothing else far enough and big enough
    assert pick_views(pixels, 3, min_pixels=1) == [(0, 1), (5, 1), (15, 0)]


def test_picture_size_follows_the_pairs_and_the_scale() -> None:
    a = np.zeros((10, 20, 3), np.float32)
    b = np.zeros((14, 12, 3), np.float32)
    picture = before_after_picture([FramePair("a", a, a), FramePair("b", b, b)], title="t", scale=2.0)
    tallest = LABEL_H + 2 * 14 * 2 + GAP
    assert picture.dtype == np.uint8
    assert picture.shape == (LABEL_H + 4 + tallest, 64 + 20 * 2 + GAP + 12 * 2, 3)


def test_bright_images_are_clipped_and_unmasked_pairs_are_not_outlined() -> None:
    bright = np.full((8, 8, 3), 3.0, np.float32)
    picture = before_after_picture([FramePair("x", bright, bright)], scale=1.0)
    panels = picture[:, 64:]  # right of the row names
    assert (panels == 255).all(axis=-1).sum() == 2 * 8 * 8
    assert not np.all(picture == OUTLINE, axis=-1).any()


def test_the_removed_object_is_outlined_in_the_original_row() -> None:
    grey = np.full((12, 12, 3), 0.5, np.float32)
    mask = np.zeros((12, 12), bool)
    mask[3:9, 3:9] = True
    picture = before_after_picture([FramePair("x", grey, grey, original_mask=mask)], scale=1.0)
    rows = np.flatnonzero(np.all(picture == OUTLINE, axis=-1).any(axis=1))
    top = LABEL_H + 4 + LABEL_H  # the head strip, then the column's label
    assert rows.min() == top + 3 and rows.max() == top + 8  # in the original panel, not the edited one


def test_no_pairs_is_an_error() -> None:
    with pytest.raises(ValueError, match="no frames"):
        before_after_picture([])
