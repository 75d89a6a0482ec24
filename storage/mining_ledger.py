"""The mining ledger: which sequences a run already mined, per mining settings.

    mining/ledger/<settings_key>/<seq_id>.json      one ``LedgerRecord``: mined by which run, with what outcome

``settings_key`` is the content key of everything that decides the scenarios (``tasks.mining_ledger``); a record
also names the log (its content key) and the reconstructed scene it was mined on, so a re-ingested or
re-reconstructed log is mined again. A record is written (atomically, ``ArtifactStore.write_json``) only after the
sequence's edits and its rows of the run's edits table are stored: a run killed while mining leaves no record and
the next run mines that sequence again.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from storage.errors import CorruptArtifactError
from storage.run_records import record_from
from storage.store import ArtifactStore, join_relpath

LEDGER_DIR = join_relpath("mining", "ledger")
RECORD_VERSION = 1


@dataclass(frozen=True)
class LedgerScenario:
    """One scenario a ledgered run accepted (``edits/<run_id>/<seq_id>/<edit_id>/``)."""

    edit_id: str
    prompt: str
    category: str


@dataclass(frozen=True)
class LedgerRecord:
    """A sequence mined under one set of mining settings.

    Attributes:
        settings_key: the mining settings' content key (the record's folder).
        seq_id: the sequence (the record's file name).
        log_key: the stored log's content key when it was mined.
        scene_hash: the reconstructed scene it was mined on (``""``: a log without camera images).
        language_hash: the language scene it was grounded in (kept for provenance, not matched).
        run_id: the run that mined it (its edits are under ``edits/<run_id>/``).
        mined_at: ISO 8601 UTC time the record was written.
        attempts: attempts made; scenarios: the accepted ones, in order.
        settings: the settings the key was computed from, as JSON data (for people reading the record).
    """

    settings_key: str
    seq_id: str
    log_key: str
    scene_hash: str
    language_hash: str
    run_id: str
    mined_at: str
    attempts: int
    scenarios: tuple[LedgerScenario, ...] = ()
    settings: dict[str, Any] = field(default_factory=dict)


def ledger_relpath(settings_key: str, seq_id: str) -> str:
    """``mining/ledger/<settings_key>/<seq_id>.json``."""
    return join_relpath(LEDGER_DIR, settings_key, f"{seq_id}.json")


def write_ledger_record(store: ArtifactStore, record: LedgerRecord) -> None:
    """Write (or replace) ``record`` atomically."""
    store.write_json(ledger_relpath(record.settings_key, record.seq_id),
                     {"record_version": RECORD_VERSION, **dataclasses.asdict(record)})


def read_ledger_record(store: ArtifactStore, settings_key: str, seq_id: str) -> LedgerRecord | None:
    """The record of ``seq_id`` under ``settings_key``, ``None`` when it was never mined with those settings.

    Raises:
        CorruptArtifactError: the file is not a valid record (naming it and the field).
    """
    relpath = ledger_relpath(settings_key, seq_id)
    if not store.exists(relpath):
        return None
    source = store.uri(relpath)
    record: LedgerRecord = record_from(LedgerRecord, store.read_json(relpath), source)
    scenarios: Any = record.scenarios  # still the file's JSON objects
    try:
        record = dataclasses.replace(record, scenarios=tuple(LedgerScenario(**s) for s in scenarios))
    except TypeError as exc:
        raise CorruptArtifactError(f"{source}: not a mining ledger record's scenarios ({exc})") from exc
    if (record.settings_key, record.seq_id) != (settings_key, seq_id):
        raise CorruptArtifactError(f"{source}: its fields name {record.settings_key}/{record.seq_id}, not its path")
    return record
