"""``simsplat run --landing DIR``: new logs ingested before the stages, the bad one quarantined, nothing twice; a run
that finds nothing new is recorded without starting a flow."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from flows.cli import app
from storage import ArtifactStore, list_logs, log_dir
from storage.landing import list_quarantined
from storage.run_records import list_run_ids, read_run_record, read_stage_matrix
from tests.tasks.landing_files import make_landing

runner = CliRunner()


def _run(store: Path, landing: Path) -> dict[str, int]:
    """One ``simsplat run --landing`` (threads, no alignment); the counts of the run it recorded."""
    before = set(list_run_ids(ArtifactStore(str(store))))
    result = runner.invoke(app, ["run", "--store", str(store), "--landing", str(landing), "--runner", "threads",
                                 "--workers", "1", "--no-align"])
    assert result.exit_code == 0, result.output
    (run_id,) = set(list_run_ids(ArtifactStore(str(store)))) - before
    record = read_run_record(ArtifactStore(str(store)), run_id)
    assert record is not None and record.status == "completed"
    return dict(record.counts)


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_run_ingests_the_landing_folder_once(prefect_api_url, shared_data: Path, tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    store, landing = tmp_path / "store", make_landing(shared_data, tmp_path / "landing")
    counts = _run(store, landing)
    assert (counts["landed"], counts["quarantined"], counts["logs"]) == (2, 1, 2)
    seq_ids = list_logs(ArtifactStore(str(store)))
    manifests = {s: (store / log_dir(s) / "_SUCCESS.json").stat().st_mtime_ns for s in seq_ids}
    (record,) = list_quarantined(ArtifactStore(str(store)))
    first_runs = list_run_ids(ArtifactStore(str(store)))
    assert record.path == str(landing / "broken") and "position_x" in record.error

    # nothing new: decided and recorded before any flow starts (no Prefect run, no Ray), every stage skipped
    monkeypatch.setattr("flows.cli.scenes.run_flow", _no_flow)
    counts = _run(store, landing)
    assert (counts["landed"], counts["quarantined"], counts["logs"]) == (0, 1, 2)
    assert {s: (store / log_dir(s) / "_SUCCESS.json").stat().st_mtime_ns for s in seq_ids} == manifests
    (idle,) = [r for r in list_run_ids(ArtifactStore(str(store))) if r not in first_runs]
    matrix = read_stage_matrix(ArtifactStore(str(store)), idle)
    assert matrix.seq_ids == tuple(seq_ids) and not matrix.problems
    assert {(matrix.cell(s, "ingest").skip_reason, matrix.cell(s, "reconstruct").skip_reason) for s in seq_ids} == {
        ("in the store before this run", "no camera images")}


def _no_flow(*args, **kwargs):
    raise AssertionError("a run with nothing new started a flow")


def test_run_names_a_landing_folder_that_is_not_there(tmp_path: Path) -> None:
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store"), "--landing", str(tmp_path / "none")])
    assert result.exit_code != 0 and "no such folder" in " ".join(result.output.replace("│", " ").split())
    assert not (tmp_path / "store").exists()
