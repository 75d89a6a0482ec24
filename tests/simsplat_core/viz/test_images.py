"""Image conversions: float to uint8, PNG bytes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from simsplat_core.viz.images import encode_png, to_uint8


def test_to_uint8_rounds_and_clips() -> None:
    out = to_uint8(np.array([[-1.0, 0.0, 0.5], [1.0 / 255.0 * 0.49, 1.0, 2.0]], np.float32))
    assert out.dtype == np.uint8 and out.tolist() == [[0, 0, 128], [0, 255, 255]]
    image = np.zeros((2, 2, 3), np.uint8)
    assert to_uint8(image) is image  # uint8 is taken as it is


def test_png_round_trip_keeps_rgb_order() -> None:
    rgb = np.zeros((5, 7, 3), np.uint8)
    rgb[..., 0] = 200  # red
    rgb[2, 3] = (0, 0, 255)  # one blue pixel
    data = encode_png(rgb)
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    decoded = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    assert decoded is not None
    back = cv2.cvtColor(decoded, cv2.COLOR_BGR2RGB)
    np.testing.assert_array_equal(back, rgb)


@pytest.mark.parametrize("bad", [np.zeros((4, 4, 3), np.float32), np.zeros((4, 4), np.uint8),
                                 np.zeros((4, 4, 4), np.uint8)])
def test_png_rejects_what_is_not_uint8_rgb(bad: np.ndarray) -> None:
    with pytest.raises(ValueError, match=r"expected an \[H, W, 3\] uint8 image"):
        encode_png(bad)
