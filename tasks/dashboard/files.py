"""Files the dashboard serves: stored artifacts by id (EXR renders as PNG a browser can show) and pictures made on
request (a query's masks), kept in memory under ids of their own.

    served = read_artifact(store, index, "edits-5b1c...")     # ServedFile(data, media_type) or None
    aid = pictures.add(rgb)                                   # "made-<hash>": a picture made for one answer
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from simsplat_core.viz.images import encode_png, to_uint8
from storage.artifact_ids import ArtifactIndex, media_type
from storage.exr import read_exr
from storage.store import ArtifactStore

#: Id prefix of pictures made on request.
MADE_PREFIX = "made-"


@dataclass(frozen=True)
class ServedFile:
    """A file's bytes and the media type it is served with."""

    data: bytes
    media_type: str


def exr_preview(store: ArtifactStore, relpath: str) -> bytes:
    """PNG bytes of an EXR's ``R``, ``G``, ``B`` channels (grey from its first channel when it has no colour).

    Raises:
        FileNotFoundError, CorruptArtifactError: naming the file.
    """
    channels = read_exr(store, relpath)
    if all(c in channels for c in "RGB"):
        rgb = np.stack([channels[c] for c in "RGB"], axis=-1)
    else:
        first = next(iter(channels.values()))
        rgb = np.repeat(first[..., None] / max(float(np.abs(first).max()), 1e-6), 3, axis=-1)
    return encode_png(to_uint8(rgb))


def read_artifact(store: ArtifactStore, index: ArtifactIndex, aid: str, *, raw: bool = False) -> ServedFile | None:
    """The file ``aid`` names (an EXR as a PNG preview unless ``raw``); ``None`` when no servable file has it.

    Raises:
        CorruptArtifactError: the EXR cannot be decoded (naming the file).
    """
    relpath = index.resolve(aid)
    if relpath is None:
        return None
    kind = media_type(relpath) or "application/octet-stream"
    if kind == "image/x-exr" and not raw:
        return ServedFile(exr_preview(store, relpath), "image/png")
    return ServedFile(store.read_bytes(relpath), kind)


class MadePictures:
    """Pictures made for an answer (query masks), kept in memory, the oldest dropped beyond ``capacity``."""

    def __init__(self, capacity: int = 256) -> None:
        self._capacity = capacity
        self._pictures: OrderedDict[str, bytes] = OrderedDict()
        self._lock = threading.Lock()

    def add(self, rgb: np.ndarray) -> str:
        """Keep ``[H, W, 3]`` uint8 (or float in [0, 1]) ``rgb`` as PNG; returns its id."""
        data = encode_png(to_uint8(rgb))
        aid = MADE_PREFIX + hashlib.sha256(data).hexdigest()[:24]
        with self._lock:
            self._pictures[aid] = data
            self._pictures.move_to_end(aid)
            while len(self._pictures) > self._capacity:
                self._pictures.popitem(last=False)
        return aid

    def get(self, aid: str) -> ServedFile | None:
        with self._lock:
            data = self._pictures.get(aid)
        return None if data is None else ServedFile(data, "image/png")
