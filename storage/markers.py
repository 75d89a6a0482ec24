"""Completion markers: a stage's output directory is *done* when its marker carries the input key and the
directory still agrees with what the marker recorded.

The marker is ``<relpath>/_SUCCESS.json`` = ``{"key": <content key>, ...info, "integrity": {...}}``. Its name
starts with ``_``, so ``ArtifactStore.staged_directory`` commits it last on object stores; write it inside
the staged directory, after every other file of the group, so that output group and marker appear together.
``mark_done`` records the size (and checksum) of every file already in the directory (``storage.integrity``);
``is_done`` and ``intact_marker`` check them before a stage reuses the output, so a corrupt artifact is reported
and recomputed rather than reused.

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
from storage.integrity import intact, seal
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


def intact_marker(store: ArtifactStore, relpath: str, key: str) -> dict[str, Any] | None:
    """The marker of ``relpath`` when it holds a complete output of inputs with content key ``key`` that still agrees
    with its manifest (``storage.integrity.check``, checksums included), else ``None``: absent, another key, or
    corrupt (then a warning names each disagreeing file and the stage recomputes it)."""
    marker = read_marker(store, relpath)
    if marker is None or marker["key"] != key:
        return None
    return marker if intact(store, relpath, marker, MARKER_NAME) else None


def is_done(store: ArtifactStore, relpath: str, key: str) -> bool:
    """Whether ``relpath`` holds a complete, intact output produced from inputs with content key ``key``."""
    return intact_marker(store, relpath, key) is not None


def mark_done(store: ArtifactStore, relpath: str, key: str, info: dict[str, Any] | None = None) -> None:
    """Write the marker of ``relpath`` (atomically): ``{"key": key, **info}`` sealed with the size and checksum of
    every file already under ``relpath`` (``storage.integrity.seal``), so write it last."""
    info = dict(info or {})
    if "key" in info:
        raise ValueError("mark_done: 'key' is reserved in info")
    store.write_json(marker_path(relpath), seal(store, relpath, {"key": key, **info}, exclude=(MARKER_NAME,)))
