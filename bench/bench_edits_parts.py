"""Benchmark: rows kept when writers append to one table at once, read-modify-write of one file against one part per
append (``storage.table_parts``), and what reading parts costs.

    .venv/bin/python bench/bench_edits_parts.py [--writers 4] [--appends 8]

Writers are separate processes released together by a barrier and share no lock, as Ray workers on several
machines writing to an object store do (a local directory stands in for it: without the lock, replacing one file
is the same last-writer-wins). The single-file writer reads the table, adds its row and writes it back; the parted
writer adds a part. Then the read time of a table of 32 rows as 1 file, as 32 parts and as 1 compacted part
(medians of 20 reads). Writes ``bench/results/edits_parts.json``.
"""

from __future__ import annotations

import argparse
import logging
import multiprocessing
import statistics
import tempfile
import time
from pathlib import Path

import pyarrow as pa
from run_info import load_average, machine_info, write_json_result

from storage import ArtifactStore
from storage.table_parts import PartedTable

logger = logging.getLogger("bench.edits_parts")

SCHEMA = pa.schema([pa.field("writer", pa.int64(), nullable=False), pa.field("row", pa.int64(), nullable=False)],
                   metadata={"schema_name": "bench_rows", "schema_version": "1"})
SINGLE_FILE = "table/rows.parquet"


def _row(writer: int, index: int) -> pa.Table:
    return pa.table({"writer": [writer], "row": [index]}, schema=SCHEMA)


def _append_single_file(root: str, writer: int, appends: int, start) -> None:
    store = ArtifactStore(root)
    start.wait()
    for index in range(appends):
        before = store.read_table(SINGLE_FILE, SCHEMA) if store.exists(SINGLE_FILE) else SCHEMA.empty_table()
        store.write_table(SINGLE_FILE, pa.concat_tables([before, _row(writer, index)]), SCHEMA)


def _append_parts(root: str, writer: int, appends: int, start) -> None:
    table = PartedTable(ArtifactStore(root), "table", "rows", SCHEMA)
    start.wait()
    for index in range(appends):
        table.append(_row(writer, index))


def _rows_kept(target, writers: int, appends: int) -> tuple[int, float]:
    """Rows found after ``writers`` processes each appended ``appends`` rows at once, and the wall time."""
    spawn = multiprocessing.get_context("spawn")
    with tempfile.TemporaryDirectory() as root:
        start = spawn.Barrier(writers + 1)
        procs = [spawn.Process(target=target, args=(root, w, appends, start)) for w in range(writers)]
        for proc in procs:
            proc.start()
        start.wait()
        began = time.perf_counter()
        for proc in procs:
            proc.join()
        seconds = time.perf_counter() - began
        store = ArtifactStore(root)
        if target is _append_single_file:
            return store.read_table(SINGLE_FILE, SCHEMA).num_rows, seconds
        return PartedTable(store, "table", "rows", SCHEMA).read().num_rows, seconds


def _read_ms(read, reps: int = 20) -> float:
    times = []
    for _ in range(reps):
        began = time.perf_counter()
        read()
        times.append(time.perf_counter() - began)
    return 1000 * statistics.median(times)


def _read_costs(rows: int) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as root:
        store = ArtifactStore(root)
        store.write_table(SINGLE_FILE, pa.concat_tables([_row(0, i) for i in range(rows)]), SCHEMA)
        parted = PartedTable(store, "parted", "rows", SCHEMA)
        for index in range(rows):
            parted.append(_row(0, index))
        costs = {"one_file_ms": _read_ms(lambda: store.read_table(SINGLE_FILE, SCHEMA)),
                 f"{rows}_parts_ms": _read_ms(parted.read)}
        parted.compact()
        costs["compacted_ms"] = _read_ms(parted.read)
        return costs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--writers", type=int, default=4)
    parser.add_argument("--appends", type=int, default=8)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    expected = args.writers * args.appends
    load_before = load_average()
    single, single_s = _rows_kept(_append_single_file, args.writers, args.appends)
    parts, parts_s = _rows_kept(_append_parts, args.writers, args.appends)
    costs = _read_costs(32)
    logger.info("%d writers x %d appends at once: one file kept %d of %d rows (%.2f s), parts kept %d (%.2f s)",
                args.writers, args.appends, single, expected, single_s, parts, parts_s)
    logger.info("reading 32 rows: %s", ", ".join(f"{k} {v:.2f}" for k, v in costs.items()))
    write_json_result({"machine": machine_info(), "load_average_before": load_before,
                       "load_average_after": load_average(), "writers": args.writers, "appends_each": args.appends,
                       "rows_expected": expected, "rows_kept": {"one_file": single, "parts": parts},
                       "append_seconds": {"one_file": single_s, "parts": parts_s}, "read_32_rows": costs},
                      args.out / "edits_parts.json")


if __name__ == "__main__":
    main()
