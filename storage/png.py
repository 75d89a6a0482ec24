"""PNG previews (contact sheets, novel views) written atomically to a local path or an object-store URI."""

from __future__ import annotations

import logging
import os

import numpy as np

from simsplat_core.viz.images import encode_png
from storage.store import ArtifactStore

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
    if not target.lower().endswith(".png"):
        raise ValueError(f"{target}: a PNG file name must end in .png")
    try:
        encoded = encode_png(rgb)
    except OSError as exc:
        raise OSError(f"{target}: {exc}") from exc
    parent, _, name = target.rstrip("/").rpartition("/")
    if "://" not in target:
        parent, name = os.path.split(os.path.abspath(target))
    store = ArtifactStore(parent or ".")
    store.write_bytes(name, encoded)
    logger.info("wrote %s (%d x %d)", store.uri(name), rgb.shape[1], rgb.shape[0])
    return store.uri(name)
