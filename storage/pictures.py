"""Picture files: PNG previews (contact sheets, novel views) written atomically to a local path or an object-store
URI, and MP4 encoding (the edits' bird's-eye animations)."""

from __future__ import annotations

import logging
import os
import tempfile

import cv2
import numpy as np

from simsplat_core.viz.images import encode_png
from storage.store import ArtifactStore
from storage.uris import is_uri, split_name

logger = logging.getLogger(__name__)


def write_png(target: str | os.PathLike[str], rgb: np.ndarray) -> str:
    """Encode ``[H, W, 3]`` uint8 RGB as PNG and write it to ``target`` atomically; returns its URI.

    ``target`` is a local path or a URI understood by ``pyarrow.fs`` (``s3://bucket/view.png``).

    Raises:
        ValueError: ``rgb`` is not ``[H, W, 3]`` uint8, or ``target`` does not end in ``.png``.
        OSError: encoding failed.
    """
    target = os.fspath(target)
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ValueError(f"{target}: expected an [H, W, 3] uint8 image, got {rgb.shape} {rgb.dtype}")
    parent, name = split_name(target)
    if not name.lower().endswith(".png"):
        raise ValueError(f"{target}: a PNG file name must end in .png")
    try:
        encoded = encode_png(rgb)
    except OSError as exc:
        raise OSError(f"{target}: {exc}") from exc
    if not is_uri(target):
        parent, name = os.path.split(os.path.abspath(target))
    store = ArtifactStore(parent or ".")
    store.write_bytes(name, encoded)
    logger.info("wrote %s (%d x %d)", store.uri(name), rgb.shape[1], rgb.shape[0])
    return store.uri(name)


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
