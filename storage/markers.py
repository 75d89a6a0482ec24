"""Completion markers: a stage's output directory is *done* when its marker carries the input key.

The marker is ``<relpath>/_SUCCESS.json`` = ``{"key": <content key>, ...info}``. Its name starts
with ``_``, so ``ArtifactStore.staged_directory`` commits it last on object stores; write it inside
the staged directory so that output group and marker appear together.

Usage in a stage::

    key = content_key(inputs, config)
    if not is_done(store, out_dir, key):
        with store.staged_directory(out_dir) as tmp:
            ...  # write outputs under tmp
            mark_done(store, tmp, key, {"rows": n})
"""

from __future__ import annotations

import logging
from typing import Any

from storage.errors import CorruptArtifactError
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

MARKER_NAME = "_SUCCESS.json"


def marker_path(relpath: str) -> str:
    return join_relpath(relpath, MARKER_NAME)


def read_marker(store: ArtifactStore, relpath: str) -> dict[str, Any] | None:
    """The marker of directory ``relpath``, or ``None`` when absent or unreadable (treated as not done)."""
    path = marker_path(relpath)
    if not store.exists(path):
        return None
    try:
        marker = store.read_json(path)
    except (CorruptArtifactError, FileNotFoundError) as exc:
        logger.warning("ignoring unreadable marker: %s", exc)
        return None
    if not isinstance(marker, dict) or not isinstance(marker.get("key"), str):
        logger.warning("ignoring marker without a key: %s", store.uri(path))
        return None
    return marker


def is_done(store: ArtifactStore, relpath: str, key: str) -> bool:
    """Whether ``relpath`` holds a complete output produced from inputs with content key ``key``."""
    marker = read_marker(store, relpath)
    return marker is not None and marker["key"] == key


def mark_done(store: ArtifactStore, relpath: str, key: str, info: dict[str, Any] | None = None) -> None:
    """Write the marker of ``relpath`` (atomically): ``{"key": key, **info}``."""
    info = dict(info or {})
    if "key" in info:
        raise ValueError("mark_done: 'key' is reserved in info")
    store.write_json(marker_path(relpath), {"key": key, **info})
