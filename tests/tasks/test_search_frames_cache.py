"""Search preparation with the per-log search-facts cache: identical facts, only new logs derived, a corrupt or
stale entry recomputed."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

import tasks.search as search_task
from simsplat_core.search.frames import ObjectFrames, log_frames
from simsplat_core.world.config import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import ArtifactStore, write_scene_log
from storage.search_frames import search_frames_cache

SEEDS = (61, 62, 63)


@pytest.fixture(scope="module")
def logs() -> list:
    config = WorldConfig(num_frames=20, render_images=False)
    return [generate_log(seed=seed, config=config) for seed in SEEDS]


@pytest.fixture
def store(tmp_path: Path, logs: list) -> str:
    root = str(tmp_path / "store")
    for log in logs[:2]:
        write_scene_log(ArtifactStore(root), log)
    return root


@pytest.fixture
def derived(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The seq_ids whose facts ``tasks.search`` derives (not read from the cache), in call order."""
    calls: list[str] = []

    def counting(log, *args, **kwargs):
        calls.append(log.seq_id)
        return log_frames(log, *args, **kwargs)

    monkeypatch.setattr(search_task, "log_frames", counting)
    return calls


def _assert_same(expected: dict[str, ObjectFrames], actual: dict[str, ObjectFrames]) -> None:
    assert list(actual) == list(expected)
    for oid, e in expected.items():
        a = actual[oid]
        for name, value in vars(e).items():
            other = getattr(a, name)
            if isinstance(value, np.ndarray):
                assert other.dtype == value.dtype and other.shape == value.shape, f"{oid}.{name}"
                assert np.array_equal(value, other, equal_nan=value.dtype.kind == "f"), f"{oid}.{name}"
            else:
                assert type(other) is type(value) and other == value, f"{oid}.{name}"


def test_cached_facts_equal_fresh_ones_and_only_a_new_log_is_derived(store: str, logs: list,
                                                                      derived: list[str]) -> None:
    first = search_task.load_store(store)
    assert derived == [log.seq_id for log in logs[:2]]
    again = search_task.load_store(store)
    assert derived == [log.seq_id for log in logs[:2]]  # nothing derived: every log cached
    for fresh, cached in zip(first, again):
        _assert_same(log_frames(fresh.log), cached.objects)
    write_scene_log(ArtifactStore(store), logs[2])
    grown = search_task.load_store(store)
    assert derived[2:] == [logs[2].seq_id]
    assert [i.log.seq_id for i in grown] == sorted(log.seq_id for log in logs)


def test_a_corrupt_entry_is_recomputed_with_a_warning(store: str, logs: list, derived: list[str],
                                                      caplog: pytest.LogCaptureFixture) -> None:
    search_task.load_store(store)
    cache = search_frames_cache(ArtifactStore(store))
    seq_id = logs[0].seq_id
    ArtifactStore(store).write_bytes(cache.relpath(seq_id), b"not parquet")
    with caplog.at_level(logging.WARNING, logger="storage.keyed_tables"):
        items = search_task.load_store(store)
    assert derived[2:] == [seq_id]
    assert any(cache.relpath(seq_id) in r.getMessage() for r in caplog.records)
    item = next(i for i in items if i.log.seq_id == seq_id)
    _assert_same(log_frames(item.log), item.objects)
    derived.clear()
    search_task.load_store(store)
    assert derived == []  # the recomputed entry was written back


def test_a_code_change_invalidates_every_entry(store: str, logs: list, derived: list[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    search_task.load_store(store)
    monkeypatch.setattr(search_task, "search_facts_digest", lambda: "other-code")
    search_task.load_store(store)
    assert derived == [log.seq_id for log in logs[:2]] * 2


def test_read_only_callers_leave_no_cache(store: str, logs: list) -> None:
    search_task.load_searchable(ArtifactStore(store), logs[0].seq_id, write_cache=False)
    assert not ArtifactStore(store).exists(search_frames_cache(ArtifactStore(store)).relpath(logs[0].seq_id))
