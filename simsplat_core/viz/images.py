"""Conversions every picture writer needs: float images to uint8, uint8 RGB to PNG bytes, frames to MP4 bytes."""

from __future__ import annotations

import os
import tempfile

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


def encode_mp4(frames: list[np.ndarray] | tuple[np.ndarray, ...], fps: float = 10.0) -> bytes:
    """MP4 (MPEG-4 part 2, ``mp4v``) bytes of ``[H, W, 3]`` uint8 RGB frames of one size, at ``fps``.

    OpenCV's writer needs a file, so the video goes through a temporary one.

    Raises:
        ValueError: no frames, or frames of different shapes / not uint8 RGB.
        OSError: OpenCV could not open a writer or wrote nothing.
    """
    if not frames:
        raise ValueError("encode_mp4: no frames")
    shape = np.shape(frames[0])
    for k, frame in enumerate(frames):
        if np.shape(frame) != shape or np.asarray(frame).dtype != np.uint8 or len(shape) != 3 or shape[2] != 3:
            raise ValueError(f"encode_mp4: frame {k} is {np.shape(frame)} {np.asarray(frame).dtype}, expected "
                             f"{shape} uint8 RGB like frame 0")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "video.mp4")
        writer = cv2.VideoWriter(path, cv2.VideoWriter.fourcc(*"mp4v"), float(fps), (int(shape[1]), int(shape[0])))
        if not writer.isOpened():
            raise OSError("OpenCV could not open an MP4 writer (mp4v)")
        try:
            for frame in frames:
                writer.write(cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_RGB2BGR))
        finally:
            writer.release()
        with open(path, "rb") as fh:
            data = fh.read()
    if not data:
        raise OSError("OpenCV wrote an empty MP4")
    return data
