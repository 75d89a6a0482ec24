"""Concurrent appends to one run's edits table keep every row exactly once: threads of one process, and processes
that share no lock (on an object store between machines nothing serialises them)."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ThreadPoolExecutor

from storage import ArtifactStore
from storage.edits import EditRecord, append_edit_records, compact_edit_records, read_edit_records
from tests.s3_server import S3Server

RUN = "mine-concurrent"


def _record(writer: int, index: int) -> EditRecord:
    return EditRecord(run_id=RUN, seq_id=f"seq{writer}", edit_id=f"e{index}", prompt=f"prompt {writer}/{index}",
                      command_json="", status="refused", failure_reason="not_found: nothing")


def _append_rows(root: str, writer: int, count: int, start=None) -> None:
    store = ArtifactStore(root)
    if start is not None:  # every writer ready: they append at the same time
        start.wait()
    for index in range(count):
        append_edit_records(store, [_record(writer, index)])


def _prompts(store: ArtifactStore) -> list[str]:
    return sorted(r.prompt for r in read_edit_records(store, RUN))


def _expected(writers: int, count: int) -> list[str]:
    return sorted(_record(w, i).prompt for w in range(writers) for i in range(count))


def test_sixteen_threads_appending_at_once_keep_every_row(tmp_path) -> None:
    store = ArtifactStore(str(tmp_path))
    with ThreadPoolExecutor(16) as pool:
        list(pool.map(lambda w: _append_rows(str(tmp_path), w, 2), range(16)))
    assert _prompts(store) == _expected(16, 2)
    assert compact_edit_records(store, RUN) == 32 and _prompts(store) == _expected(16, 2)


def test_processes_appending_to_an_object_store_keep_every_row(s3_server: S3Server) -> None:
    root = s3_server.fresh_uri("store", "edits-concurrent")
    spawn = multiprocessing.get_context("spawn")  # fresh interpreters: no lock of this process is shared
    ready = spawn.Barrier(2)
    writers = [spawn.Process(target=_append_rows, args=(root, w, 8, ready)) for w in range(2)]
    for proc in writers:
        proc.start()
    for proc in writers:
        proc.join(120)
    assert [p.exitcode for p in writers] == [0, 0]
    store = ArtifactStore(root)
    assert _prompts(store) == _expected(2, 8)
    assert [r.attempt for r in read_edit_records(store, RUN)] == [1] * 16
    assert compact_edit_records(store, RUN) == 16 and _prompts(store) == _expected(2, 8)
