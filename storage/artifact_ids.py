"""Artifact ids: opaque names under which a reader (the dashboard) serves a file of the store, never a path.

    aid = artifact_id("edits/run-1/synth-000000/7ca3/bev.mp4")    # "edits-5b1c...": the top folder, then a hash
    relpath = ArtifactIndex(store).resolve(aid)                     # the file, or None

An id is the store folder the file sits in (``logs``, ``edits``, ...) and the first 24 hex digits of the SHA-256 of
its relative path, so it is stable across restarts and reveals nothing a client could edit into another path.
:class:`ArtifactIndex` resolves an id by listing that one folder (once, then again only when an id is not found
and the listing is older than ``rescan_s``); only files with a servable extension, outside hidden and temporary
names, are ever listed, so no id can name anything else.
"""

from __future__ import annotations

import hashlib
import threading
import time
from dataclasses import dataclass

from storage.store import ArtifactStore, normalize_relpath

#: Store folders whose files may be served, and the extensions served with their media types.
SERVED_FOLDERS: tuple[str, ...] = ("logs", "scenes", "alignment", "edits", "runs", "searches", "datasets", "assets")
MEDIA_TYPES: dict[str, str] = {
    ".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".mp4": "video/mp4", ".exr": "image/x-exr",
    ".json": "application/json", ".md": "text/markdown; charset=utf-8", ".parquet": "application/vnd.apache.parquet",
}
_HASH_DIGITS = 24


def artifact_id(relpath: str) -> str:
    """The id of the file at ``relpath`` (``"<top folder>-<24 hex>"``).

    Raises:
        UnsafePathError: ``relpath`` is absolute or climbs out of the store.
        ValueError: the file is not in a served folder or has no servable extension.
    """
    rel = normalize_relpath(relpath)
    top = rel.split("/", 1)[0]
    if top not in SERVED_FOLDERS or "/" not in rel:
        raise ValueError(f"{rel}: not in a served store folder {list(SERVED_FOLDERS)}")
    if media_type(rel) is None:
        raise ValueError(f"{rel}: not a servable file type {sorted(MEDIA_TYPES)}")
    return f"{top}-{hashlib.sha256(rel.encode()).hexdigest()[:_HASH_DIGITS]}"


def media_type(relpath: str) -> str | None:
    """The media type a file is served with, ``None`` when it is not servable."""
    name = relpath.rsplit("/", 1)[-1].lower()
    dot = name.rfind(".")
    return MEDIA_TYPES.get(name[dot:]) if dot > 0 else None


def _servable(relpath: str) -> bool:
    parts = relpath.split("/")
    return media_type(relpath) is not None and not any(p.startswith((".", "_")) or ".tmp-" in p for p in parts)


@dataclass
class _Listing:
    ids: dict[str, str]
    at: float


class ArtifactIndex:
    """Resolves artifact ids to relative paths of one store (thread-safe; module docstring)."""

    def __init__(self, store: ArtifactStore, rescan_s: float = 2.0) -> None:
        self._store = store
        self._rescan_s = rescan_s
        self._listings: dict[str, _Listing] = {}
        self._lock = threading.Lock()

    def resolve(self, aid: str) -> str | None:
        """The relative path of the file ``aid`` names, ``None`` when no servable file has that id."""
        top, sep, digest = aid.partition("-")
        if not sep or top not in SERVED_FOLDERS or len(digest) != _HASH_DIGITS or not digest.isalnum():
            return None
        with self._lock:
            listing = self._listings.get(top)
            now = time.monotonic()
            if listing is None or (aid not in listing.ids and now - listing.at >= self._rescan_s):
                listing = _Listing(self._list(top), now)
                self._listings[top] = listing
            return listing.ids.get(aid)

    def _list(self, top: str) -> dict[str, str]:
        if not self._store.is_dir(top):
            return {}
        rels = (f"{top}/{rel}" for rel in self._store.walk(top))
        return {artifact_id(rel): rel for rel in rels if _servable(rel)}
