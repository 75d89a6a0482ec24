"""Landing records: which landing-folder logs a run already ingested, and which it quarantined.

A run that scans a landing location (``tasks.landing``) keeps two kinds of small JSON records in the store:

* ``landing/ingested/<landing key>.json``: a log ingested from the landing location under that key (the key
  of the log's files as they were: ``tasks.landing.landing_key``), with the ``seq_id`` it was stored as; a log
  whose key has a record and whose ``logs/<seq_id>`` is still complete is not decoded again.
* ``landing/quarantine/<name>.json``: a log that failed to load, with its path, source, error and when it was
  first seen and last tried; it is retried only when its landing key changes (the file was replaced or touched).

Every write is atomic (``ArtifactStore.write_json``).
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass
from typing import TypeVar

from storage.errors import CorruptArtifactError
from storage.keys import content_key
from storage.store import ArtifactStore, join_relpath
from storage.uris import split_name

LANDING_DIR = "landing"
INGESTED_DIR = join_relpath(LANDING_DIR, "ingested")
QUARANTINE_DIR = join_relpath(LANDING_DIR, "quarantine")

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")
_Record = TypeVar("_Record")


@dataclass(frozen=True)
class IngestedRecord:
    """A landing log that a run ingested.

    Attributes:
        key: the landing key of its files when ingested.
        source: the log source that loaded it.
        path: where it was in the landing location.
        seq_id: the sequence it was stored as (``logs/<seq_id>``).
        ingested_at: ISO 8601 UTC time of the ingest.
    """

    key: str
    source: str
    path: str
    seq_id: str
    ingested_at: str


@dataclass(frozen=True)
class QuarantineRecord:
    """A landing log that failed to load.

    Attributes:
        path: where it is in the landing location.
        source: the log source that recognised it (and failed to load it).
        error: the loader's error (type and message).
        key: the landing key of its files when it last failed (unchanged: not retried).
        first_seen: ISO 8601 UTC time of its first failure.
        last_tried: ISO 8601 UTC time of its latest failure.
    """

    path: str
    source: str
    error: str
    key: str
    first_seen: str
    last_tried: str


def ingested_relpath(key: str) -> str:
    """``landing/ingested/<key>.json``."""
    return join_relpath(INGESTED_DIR, f"{_safe(key)}.json")


def quarantine_relpath(path: str) -> str:
    """``landing/quarantine/<name>-<hash of the path>.json`` of the landing log at ``path`` (the hash keeps two
    logs with the same name in different folders apart)."""
    name = _safe(split_name(path)[1]) or "log"
    return join_relpath(QUARANTINE_DIR, f"{name[:80]}-{content_key('landing-path', path)[:12]}.json")


def _safe(name: str) -> str:
    return _UNSAFE.sub("_", name).lstrip(".")


def _read(store: ArtifactStore, relpath: str) -> dict | None:
    if not store.exists(relpath):
        return None
    value = store.read_json(relpath)
    if not isinstance(value, dict):
        raise CorruptArtifactError(f"{store.uri(relpath)}: a landing record must be a JSON object")
    return value


def _from_dict(cls: type[_Record], value: dict, store: ArtifactStore, relpath: str) -> _Record:
    try:
        return cls(**value)
    except TypeError as exc:
        raise CorruptArtifactError(f"{store.uri(relpath)}: not a {cls.__name__} ({exc})") from exc


def read_ingested(store: ArtifactStore, key: str) -> IngestedRecord | None:
    """The record of the landing log ingested under ``key``, or ``None``.

    Raises:
        CorruptArtifactError: the record is not a valid ``IngestedRecord`` (naming the file).
    """
    relpath = ingested_relpath(key)
    value = _read(store, relpath)
    return None if value is None else _from_dict(IngestedRecord, value, store, relpath)


def write_ingested(store: ArtifactStore, record: IngestedRecord) -> None:
    """Write ``record`` (atomically)."""
    store.write_json(ingested_relpath(record.key), asdict(record))


def read_quarantine(store: ArtifactStore, path: str) -> QuarantineRecord | None:
    """The quarantine record of the landing log at ``path``, or ``None`` when it is not quarantined.

    Raises:
        CorruptArtifactError: the record is not a valid ``QuarantineRecord`` (naming the file).
    """
    relpath = quarantine_relpath(path)
    value = _read(store, relpath)
    return None if value is None else _from_dict(QuarantineRecord, value, store, relpath)


def write_quarantine(store: ArtifactStore, record: QuarantineRecord) -> None:
    """Write ``record`` (atomically, replacing an older record of the same path)."""
    store.write_json(quarantine_relpath(record.path), asdict(record))


def clear_quarantine(store: ArtifactStore, path: str) -> bool:
    """Remove the quarantine record of ``path`` (it loaded now); whether there was one."""
    return store.delete(quarantine_relpath(path))


def list_quarantined(store: ArtifactStore) -> list[QuarantineRecord]:
    """Every quarantine record in the store, sorted by path."""
    records = []
    for name in store.listdir(QUARANTINE_DIR):
        relpath = join_relpath(QUARANTINE_DIR, name)
        value = _read(store, relpath) if name.endswith(".json") and not name.startswith(".") else None
        if value is not None:
            records.append(_from_dict(QuarantineRecord, value, store, relpath))
    return sorted(records, key=lambda r: r.path)
