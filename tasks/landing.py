"""The landing location a run scans for new driving logs: what is new, what is already in, what is quarantined.

``scan_landing`` finds every log of a registered source under the landing folder
(``simsplat_core.data.registry.find_logs``) and sorts it, without decoding anything, by its *landing key*: a
content key of the source name and, for every file of the log (the file itself, or each file under its folder),
its path inside the log, size in bytes and modification time in nanoseconds. Stat calls only, so a scan over
large logs takes moments; a log replaced, appended to or touched gets a new key.

* **already**: a run ingested the log under this key (``storage.landing`` ingested record) and ``logs/<seq_id>``
  is still complete in the store (a quarantine record left from an earlier, failing version of it is cleared);
* **quarantined_known**: the log failed to load under this very key (``storage.landing`` quarantine record): it
  is not retried until it changes;
* **new**: anything else (never seen, changed since, or its stored log was removed).

A landing location in an object store (``s3://bucket/prefix?endpoint_override=...``) is scanned through a local
mirror (``storage.remote_folder``: only new or changed objects are downloaded, each mirrored file keeps its object's
size and modification time, so the landing key is that of the objects); its logs are named by their URI
(``LandingLog.path``), and the ingest of one downloads that log to a temporary folder on whichever worker runs it.

``land_log`` ingests one new log (``tasks.logs``' decode and store): on success it records the ingest and clears
an older quarantine record; when decoding fails it writes the quarantine record (path, source, error, first seen,
last tried) and returns the reason instead of raising, so one bad file never stops the others.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import pyarrow.fs as pafs
from prefect import task
from prefect.cache_policies import NO_CACHE

from storage import ArtifactStore, content_key, read_log_manifest
from storage.landing import (
    IngestedRecord,
    QuarantineRecord,
    clear_quarantine,
    read_ingested,
    read_quarantine,
    write_ingested,
    write_quarantine,
)
from storage.remote_folder import default_mirror_dir, fetched, is_remote, list_remote_files, mirror_folder
from storage.run_records import utc_now
from storage.uris import is_uri, join_uri, split_query
from tasks.logs import DecodedLog, StoredLog, decode_real_log, store_real_log
from tasks.retry_policy import STAGE_RETRIES
from tasks.run_record import error_text

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class LandingLog:
    """One log found in the landing location.

    Attributes:
        source: the registered source that recognises it.
        path: its file or folder (absolute), or its URI in a landing location in an object store.
        key: its landing key (module docstring).
    """

    source: str
    path: str
    key: str


@dataclass(frozen=True)
class LandingPlan:
    """What a scan of the landing location found (each in path order).

    Attributes:
        new: logs to ingest now.
        already: logs ingested before under the same key, with their stored ``seq_id``.
        quarantined_known: logs that failed to load before and have not changed since, with their record.
    """

    new: tuple[LandingLog, ...]
    already: tuple[tuple[LandingLog, str], ...]
    quarantined_known: tuple[tuple[LandingLog, QuarantineRecord], ...]


@dataclass(frozen=True)
class LandingOutcome:
    """What ``land_log`` did with one new log: ``stored`` when it was ingested, else ``error`` (quarantined)."""

    log: LandingLog
    stored: StoredLog | None
    error: str = ""

    @property
    def label(self) -> str:
        """The stored sequence, or the file name and ``quarantined`` (for progress lines)."""
        return self.stored.summary.seq_id if self.stored else f"{Path(self.log.path).name} (quarantined)"


def check_landing(landing: str) -> None:
    """Fail early when the landing location cannot be scanned (a local folder or an object-store folder).

    Raises:
        FileNotFoundError: the folder does not exist (named).
        CredentialsInUriError: the URI carries credentials (``storage.uris``).
    """
    if is_remote(landing):
        list_remote_files(landing)
    else:
        landing_folder(landing)


def landing_folder(landing: str) -> Path:
    """The local folder of a landing location given as a path or a ``file://`` URI.

    Raises:
        ValueError: a URI of an object store (those are mirrored: ``scan_landing``), naming it.
        FileNotFoundError: the folder does not exist (named).
    """
    if is_uri(landing):
        filesystem, path = pafs.FileSystem.from_uri(landing)
        if not isinstance(filesystem, pafs.LocalFileSystem):
            raise ValueError(f"landing location {landing!r}: not a local folder ({filesystem.type_name})")
        landing = path
    folder = Path(landing)
    if not folder.is_dir():
        raise FileNotFoundError(f"landing location {landing}: no such folder")
    return folder


def _log_files(path: Path) -> list[Path]:
    """The files of a log: the file itself, or every non-hidden file under its folder, sorted."""
    if not path.is_dir():
        return [path]
    files: list[Path] = []
    for folder, dirs, names in os.walk(path):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        files.extend(Path(folder, name) for name in names if not name.startswith("."))
    return sorted(files)


def landing_key(source: str, path: str | Path) -> str:
    """The landing key of the log at ``path`` (module docstring): source, and per file its path inside the log,
    size (bytes) and modification time (ns)."""
    path = Path(path)
    entries = []
    for file in _log_files(path):
        stat = file.stat()
        entries.append((file.relative_to(path).as_posix() if file != path else "", stat.st_size, stat.st_mtime_ns))
    return content_key("landing-log", source, entries)


def _already_stored(store: ArtifactStore, key: str) -> str | None:
    """The ``seq_id`` a landing log with ``key`` was ingested as, when that log is still complete in the store."""
    record = read_ingested(store, key)
    if record is None or read_log_manifest(store, record.seq_id) is None:
        return None
    return record.seq_id


def scan_landing(store_root: str, landing: str) -> LandingPlan:
    """Sort every log in the landing location into new, already ingested and known-quarantined (module docstring).

    Raises:
        ValueError, FileNotFoundError: see ``landing_folder``.
        UnknownLogSourceError: two sources claim one path (a registry bug).
    """
    from simsplat_core.data.registry import find_logs

    store = ArtifactStore(store_root)
    new: list[LandingLog] = []
    already: list[tuple[LandingLog, str]] = []
    quarantined: list[tuple[LandingLog, QuarantineRecord]] = []
    remote = is_remote(landing)
    folder = mirror_folder(landing, default_mirror_dir(landing)) if remote else landing_folder(landing)
    for source, path in find_logs(folder):
        name = join_uri(landing, Path(path).relative_to(folder).as_posix()) if remote else os.path.abspath(path)
        found = LandingLog(source, name, landing_key(source, path))
        seq_id = _already_stored(store, found.key)
        if seq_id is not None:
            already.append((found, seq_id))
            if clear_quarantine(store, found.path):  # an identical copy of it was ingested since it failed
                logger.info("landing %s: already stored as %s, out of quarantine", found.path, seq_id)
            continue
        record = read_quarantine(store, found.path)
        if record is not None and record.key == found.key:
            quarantined.append((found, record))
        else:
            new.append(found)
    logger.info("landing %s: %d new, %d already ingested, %d quarantined and unchanged", landing, len(new),
                len(already), len(quarantined))
    return LandingPlan(tuple(new), tuple(already), tuple(quarantined))


def ingest_landing_log(store_root: str, landed: LandingLog, image_scale: float = 1.0) -> LandingOutcome:
    """Ingest one new landing log, recording it; a log that fails to decode is quarantined (module docstring).

    Errors writing the store are raised (the log is not at fault).
    """
    store = ArtifactStore(store_root)
    started = time.perf_counter()
    try:
        decoded = _decode_landed(landed, image_scale)
    except Exception as exc:  # any decoding failure is the log's: quarantine it and go on with the others
        error = str(exc) if isinstance(exc, FetchedLogError) else error_text(exc)
        now = utc_now()
        previous = read_quarantine(store, landed.path)
        write_quarantine(store, QuarantineRecord(landed.path, landed.source, error, landed.key,
                                                 previous.first_seen if previous else now, now))
        logger.warning("landing %s: quarantined (%s)", landed.path, error)
        return LandingOutcome(landed, None, error)
    stored = store_real_log(store_root, decoded, started)
    write_ingested(store, IngestedRecord(landed.key, landed.source, landed.path, stored.summary.seq_id, utc_now()))
    if clear_quarantine(store, landed.path):
        logger.info("landing %s: loads now, out of quarantine", landed.path)
    return LandingOutcome(landed, stored)


class FetchedLogError(Exception):
    """A landing log fetched from an object store failed to decode; the message is the loader's error
    (``"<type>: <message>"``) with the temporary local copy named by the log's location in the bucket instead."""


def _decode_landed(landed: LandingLog, image_scale: float) -> DecodedLog:
    """Decode a landing log; one in an object store from a temporary local copy (recorded under its URI).

    Raises:
        FetchedLogError: a log from an object store failed to decode (its files named by their bucket paths).
    """
    if not is_remote(landed.path):
        return decode_real_log(landed.source, landed.path, image_scale)
    with fetched(landed.path) as local:
        try:
            decoded = decode_real_log(landed.source, str(local), image_scale)
        except Exception as exc:
            raise FetchedLogError(error_text(exc).replace(str(local), split_query(landed.path)[0])) from exc
    return dataclasses.replace(decoded, path=landed.path)


@task(name="land-log", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def land_log(store_root: str, landed: LandingLog, image_scale: float = 1.0) -> LandingOutcome:
    """``ingest_landing_log`` as a task of the run's ingest fan-out."""
    return ingest_landing_log(store_root, landed, image_scale)
