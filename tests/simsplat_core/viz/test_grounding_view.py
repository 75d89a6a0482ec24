"""Grounding pictures: the outline lands in the camera that matched, relevance maps share one colour scale."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.viz.grounding_view import grounding_picture, relevance_image, relevance_range

H, W, GAP = 16, 24, 4
YELLOW = (255, 255, 0)


def test_the_outline_is_drawn_in_the_matching_cameras_slot() -> None:
    images = [np.full((H, W, 3), 0.5, np.float32)] * 3
    masks = np.zeros((3, H, W), bool)
    masks[1, 4:12, 6:18] = True  # only the middle camera matched
    picture = grounding_picture(images, masks)
    cols = np.flatnonzero(np.all(picture == YELLOW, axis=-1).any(axis=0))
    rows = np.flatnonzero(np.all(picture == YELLOW, axis=-1).any(axis=1))
    assert cols.min() == (W + GAP) + 6 and cols.max() == (W + GAP) + 17  # the mask's border in camera 1's slot
    assert rows.min() == 4 and rows.max() == 11
    assert picture[0, 0].tolist() == [128] * 3  # camera 0 matched nothing: left as it is
    assert picture[0, W + GAP].tolist() == [round(0.5 * 0.35 * 255)] * 3  # camera 1 dimmed outside its mask
    assert picture.dtype == np.uint8


def test_relevance_range_is_robust_to_outliers() -> None:
    values = np.linspace(0.0, 1.0, 1001)
    values[-1] = 100.0  # one outlier
    low, high = relevance_range(values)
    assert low == pytest.approx(np.percentile(values, 2)) and high < 2.0


def test_relevance_image_scales_between_low_and_high() -> None:
    ramp = np.tile(np.linspace(0.0, 1.0, 11, dtype=np.float32), (2, 1))
    heat = relevance_image(ramp, 0.0, 1.0)
    assert heat.shape == (2, 11, 3) and heat.dtype == np.float32 and 0.0 <= heat.min() and heat.max() <= 1.0
    # everything above high looks like high, everything below low like low
    np.testing.assert_allclose(relevance_image(ramp + 5.0, 0.0, 1.0), relevance_image(np.ones_like(ramp), 0.0, 1.0))
    np.testing.assert_allclose(relevance_image(ramp - 5.0, 0.0, 1.0), relevance_image(np.zeros_like(ramp), 0.0, 1.0))
    flat = relevance_image(np.full((3, 3), 0.7, np.float32))  # a constant map: no division by zero
    assert np.isfinite(flat).all()


def test_one_colour_scale_for_all_cameras() -> None:
    """The same value is the same colour in every camera, however different the cameras' ranges."""
    images = [np.zeros((H, W, 3), np.float32)] * 2
    relevance = np.stack([np.full((H, W), 0.2, np.float32), np.linspace(0.0, 1.0, H * W, dtype=np.float32
                                                                        ).reshape(H, W)])
    relevance[1, 0, 0] = 0.2
    picture = grounding_picture(images, np.zeros((2, H, W), bool), relevance)
    bottom = picture[H + GAP:]
    np.testing.assert_array_equal(bottom[0, 0], bottom[0, W + GAP])
