"""Landing records in the store: ingested and quarantine records round-trip, bad ones are named."""

from __future__ import annotations

from pathlib import Path

import pytest

from storage import ArtifactStore
from storage.errors import CorruptArtifactError
from storage.landing import (
    IngestedRecord,
    QuarantineRecord,
    clear_quarantine,
    ingested_relpath,
    list_quarantined,
    quarantine_relpath,
    read_ingested,
    read_quarantine,
    write_ingested,
    write_quarantine,
)


def _quarantined(path: str) -> QuarantineRecord:
    return QuarantineRecord(path, "waymo-scenario", "CorruptLogError: truncated", "k1", "t0", "t1")


def test_records_round_trip_and_clear(tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path))
    ingested = IngestedRecord("ab" * 32, "av2", "/landing/log", "seq-1", "t0")
    assert read_ingested(store, ingested.key) is None
    write_ingested(store, ingested)
    assert read_ingested(store, ingested.key) == ingested
    record = _quarantined("/landing/a/x.tfrecord")
    write_quarantine(store, record)
    assert read_quarantine(store, record.path) == record
    assert list_quarantined(store) == [record]
    assert clear_quarantine(store, record.path) and not clear_quarantine(store, record.path)
    assert read_quarantine(store, record.path) is None and list_quarantined(store) == []


def test_logs_with_one_name_in_two_folders_get_their_own_quarantine_record(tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path))
    first, second = _quarantined("/landing/a/x.tfrecord"), _quarantined("/landing/b/x.tfrecord")
    assert quarantine_relpath(first.path) != quarantine_relpath(second.path)
    assert quarantine_relpath(first.path).startswith("landing/quarantine/x.tfrecord-")
    write_quarantine(store, first)
    write_quarantine(store, second)
    assert list_quarantined(store) == [first, second]


def test_a_mangled_record_is_named(tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path))
    store.write_json(ingested_relpath("k"), {"key": "k"})
    with pytest.raises(CorruptArtifactError, match="ingested/k.json.*IngestedRecord"):
        read_ingested(store, "k")
    store.write_json(quarantine_relpath("/landing/x"), ["not", "an", "object"])
    with pytest.raises(CorruptArtifactError, match="must be a JSON object"):
        read_quarantine(store, "/landing/x")
