import numpy as np
import pytest

from simsplat_core.viz.grounding_view import grounding_picture, mask_overlay, relevance_image


def test_overlay_dims_the_rest_and_outlines_the_mask():
    image = np.full((20, 30, 3), 0.5, np.float32)
    mask = np.zeros((20, 30), bool)
    mask[5:15, 10:20] = True
    out = mask_overlay(image, mask)
    assert np.allclose(out[~mask], 0.5 * 0.35)  # outside dimmed
    assert np.allclose(out[10, 15], 0.5)  # inside kept as it is
    assert np.allclose(out[5, 15], (1.0, 1.0, 0.0))  # the border is outlined in yellow
    assert np.allclose(mask_overlay(image, np.zeros_like(mask)), image)  # no match: nothing dimmed
    with pytest.raises(ValueError, match="does not match"):
        mask_overlay(image, mask[:10])


def test_relevance_is_monotone_in_red():
    ramp = np.tile(np.linspace(-1, 1, 50, dtype=np.float32), (4, 1))
    heat = relevance_image(ramp, -1.0, 1.0)
    assert heat[0, -1, 0] > heat[0, 0, 0] and heat[0, 0, 2] > heat[0, -1, 2]


def test_picture_stacks_relevance_below_cameras():
    images = [np.zeros((16, 24, 3), np.float32)] * 3
    masks = np.zeros((3, 16, 24), bool)
    top = grounding_picture(images, masks)
    both = grounding_picture(images, masks, np.random.default_rng(0).random((3, 16, 24)))
    assert top.dtype == np.uint8 and top.shape == (16, 3 * 24 + 2 * 4, 3)
    assert both.shape == (16 + 4 + 16, top.shape[1], 3)
    with pytest.raises(ValueError, match="2 images but masks for 3"):
        grounding_picture(images[:2], masks)
