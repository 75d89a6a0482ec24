"""Mining ledger records in the store: they round-trip, and a garbled or misplaced one is named."""

from __future__ import annotations

from pathlib import Path

import pytest

from storage import ArtifactStore
from storage.errors import CorruptArtifactError
from storage.mining_ledger import (
    LedgerRecord,
    LedgerScenario,
    ledger_relpath,
    read_ledger_record,
    write_ledger_record,
)


def _record(seq_id: str = "seq-1") -> LedgerRecord:
    return LedgerRecord("k" * 64, seq_id, "log-key", "scene-hash", "language-hash", "main-1", "2026-11-28T00:00:00",
                        attempts=3, scenarios=(LedgerScenario("e1", "a car stops", "modify_vehicle"),),
                        settings={"per_sequence": 1})


def test_a_record_round_trips_under_its_settings_and_sequence(tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path))
    record = _record()
    assert read_ledger_record(store, record.settings_key, record.seq_id) is None
    write_ledger_record(store, record)
    assert read_ledger_record(store, record.settings_key, record.seq_id) == record
    assert read_ledger_record(store, "other", record.seq_id) is None
    assert read_ledger_record(store, record.settings_key, "seq-2") is None


@pytest.mark.parametrize("content", ["[1, 2]", '{"seq_id": "seq-1"}', "{not json"])
def test_a_garbled_record_is_named(tmp_path: Path, content: str) -> None:
    store = ArtifactStore(str(tmp_path))
    relpath = ledger_relpath("k" * 64, "seq-1")
    (tmp_path / relpath).parent.mkdir(parents=True)
    (tmp_path / relpath).write_text(content)
    with pytest.raises((CorruptArtifactError, ValueError), match="seq-1.json"):
        read_ledger_record(store, "k" * 64, "seq-1")


def test_a_record_in_another_sequences_file_is_refused(tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path))
    write_ledger_record(store, _record("seq-1"))
    (tmp_path / ledger_relpath("k" * 64, "seq-1")).rename(tmp_path / ledger_relpath("k" * 64, "seq-2"))
    with pytest.raises(CorruptArtifactError, match="not its path"):
        read_ledger_record(store, "k" * 64, "seq-2")
