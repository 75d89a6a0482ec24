"""``simsplat run`` as its users meet faults: a run killed with SIGKILL is resumed by the next one without redoing
what it stored, and two runs started on one store at once both finish without corrupting it. Each run is a fresh
interpreter against the session's Prefect API, on tiny worlds with the thread runner."""

from __future__ import annotations

import datetime
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from storage import ArtifactStore, list_logs, list_scenes, read_scene, read_scene_log
from storage.run_records import INTERRUPTED, STALE_AFTER_S, list_run_ids, read_run_record, read_stage_matrix
from storage.store import OLD_TAG, TMP_TAG

pytestmark = pytest.mark.orchestration

REPO = Path(__file__).resolve().parents[2]
SEQS = ["synth-000000", "synth-000001"]
#: Two tiny sequences, reconstructed one after the other (one worker), no alignment.
RUN_ARGS = ("--sequences", "2", "--runner", "threads", "--workers", "1", "--iterations", "20", "--frames", "8",
            "--width", "64", "--height", "48", "--no-align")


def _start_run(store: Path, log: Path, api_url: str) -> subprocess.Popen:
    """``simsplat run --store store`` in a fresh interpreter, its output in ``log``."""
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    env.update(PREFECT_API_URL=api_url, SIMSPLAT_PROGRESS="0",
               PYTHONPATH=os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")]))
    return subprocess.Popen([sys.executable, "-c", "from flows.cli import main; main()", "run", "--store", str(store),
                             *RUN_ARGS], stdout=log.open("w"), stderr=subprocess.STDOUT, env=env, cwd=store.parent)


def _finish(run: subprocess.Popen, log: Path, timeout_s: float = 600) -> None:
    assert run.wait(timeout=timeout_s) == 0, log.read_text()[-4000:]


def _committed_files(store: Path, markers: str = "scenes/*/*/_SUCCESS.json") -> dict[str, tuple[int, int]]:
    """``relative path -> (inode, mtime ns)`` of every file of every committed group whose marker matches
    ``markers``."""
    return {str(f.relative_to(store)): _identity(f)
            for marker in store.glob(markers) for f in marker.parent.rglob("*") if f.is_file()}


def _identity(path: Path) -> tuple[int, int]:
    """A file's inode and modification time, ns: both change when it is written again."""
    return path.stat().st_ino, path.stat().st_mtime_ns


def _check_store_reads_back(root: Path) -> None:
    """Every log and scene is complete and reads back, one scene per sequence; no staged or set-aside version is
    visible under a real name."""
    store = ArtifactStore(root)
    assert list_logs(store) == SEQS
    for seq in SEQS:
        assert read_scene_log(store, seq).num_frames == 8
        assert len(list_scenes(store, seq)) == 1
        assert read_scene(store, seq).metrics["iterations"] == 20
    visible = [p for p in store.walk("logs") + store.walk("scenes") if TMP_TAG in p or OLD_TAG in p]
    assert all(part.startswith(".") for p in visible for part in p.split("/") if TMP_TAG in part or OLD_TAG in part)


def test_a_killed_run_is_resumed_without_redoing_what_it_stored(prefect_api_url, tmp_path):
    store_root = tmp_path / "store"
    first = _start_run(store_root, tmp_path / "first.log", prefect_api_url)
    try:
        while not _committed_files(store_root):
            assert first.poll() is None, (tmp_path / "first.log").read_text()[-4000:]
            time.sleep(0.05)
    finally:
        first.send_signal(signal.SIGKILL)
        first.wait()
    stored = _committed_files(store_root)
    stored_logs = _committed_files(store_root, "logs/*/_SUCCESS.json")
    assert sorted({path.split("/")[1] for path in stored_logs}) == SEQS
    done_before = sorted({path.split("/")[1] for path in stored})
    store = ArtifactStore(store_root)
    (killed_id,) = list_run_ids(store)
    killed = read_run_record(store, killed_id)
    assert (killed.status, killed.finished_at) == ("running", None)  # the process had no chance to say more
    silent = killed.last_sign_of_life + datetime.timedelta(seconds=STALE_AFTER_S + 1)
    assert killed.observed_status(silent) == INTERRUPTED

    second = _start_run(store_root, tmp_path / "second.log", prefect_api_url)
    _finish(second, tmp_path / "second.log")
    for before in (stored, stored_logs):  # what the killed run committed was reused as it was, not rewritten
        assert {path: _identity(store_root / path) for path in before} == before
    _check_store_reads_back(store_root)
    (resumed_id,) = set(list_run_ids(store)) - {killed_id}
    assert read_run_record(store, resumed_id).observed_status() == "completed"
    matrix = read_stage_matrix(store, resumed_id)
    for seq in SEQS:
        cell = matrix.cell(seq, "reconstruct")
        assert cell.status == "completed"
        assert ("reused" in cell.note) == (seq in done_before), (seq, cell)
        assert "reused" in matrix.cell(seq, "ingest").note  # both logs were stored by the killed run


def test_two_runs_started_on_one_store_at_once_both_finish_and_leave_it_whole(prefect_api_url, tmp_path):
    store_root = tmp_path / "store"
    store_root.mkdir()
    logs = [tmp_path / f"run{k}.log" for k in range(2)]
    runs = [_start_run(store_root, log, prefect_api_url) for log in logs]
    for run, log in zip(runs, logs):
        _finish(run, log)
    _check_store_reads_back(store_root)
    store = ArtifactStore(store_root)
    run_ids = list_run_ids(store)
    assert len(run_ids) == 2
    for run_id in run_ids:
        record = read_run_record(store, run_id)
        assert (record.status, record.counts["logs"], record.counts["scenes"]) == ("completed", 2, 2)
        matrix = read_stage_matrix(store, run_id)
        assert matrix.seq_ids == tuple(SEQS) and not matrix.problems
        assert all(matrix.cell(seq, "reconstruct").status == "completed" for seq in SEQS)
