"""Conversions every picture needs: float images to uint8, uint8 RGB to PNG bytes (also what the VLM client sends)."""

from __future__ import annotations

import cv2
import numpy as np


def to_uint8(image: np.ndarray) -> np.ndarray:
    """``[..., 3]`` float in ``[0, 1]`` -> uint8 (rounded, clipped); uint8 input is returned as it is."""
    image = np.asarray(image)
    if image.dtype == np.uint8:
        return image
    return np.clip(image * 255.0 + 0.5, 0, 255).astype(np.uint8)


def encode_png(rgb: np.ndarray) -> bytes:
    """PNG bytes of an ``[H, W, 3]`` uint8 RGB image.

    Raises:
        ValueError: ``rgb`` is not ``[H, W, 3]`` uint8.
        OSError: OpenCV could not encode it.
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ValueError(f"expected an [H, W, 3] uint8 image, got {rgb.shape} {rgb.dtype}")
    ok, encoded = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise OSError("OpenCV could not encode the PNG")
    return encoded.tobytes()
