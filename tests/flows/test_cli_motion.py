"""``simsplat eval motion``: the real-data table from the samples (skipped without ../shared/data), a corrupt
Waymo record (exit code 2 naming the file, no traceback), an unknown predictor."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
from typer.testing import CliRunner

from flows.cli import app
from flows.cli.evaluate import default_real_logs

runner = CliRunner()


def test_corrupt_record_exits_2_naming_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.tfrecord"
    bad.write_bytes(b"\x10\x00\x00\x00\x00\x00\x00\x00garbage")
    result = runner.invoke(app, ["eval", "motion", "--out", str(tmp_path / "out"), "--real", str(bad),
                                 "--predictor", "constant-velocity"])
    assert result.exit_code == 2, result.output
    assert "damaged log" in result.output and "bad.tfrecord" in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "out" / "tables" / "motion.parquet").exists()


def test_unknown_predictor_and_missing_path(tmp_path: Path) -> None:
    result = runner.invoke(app, ["eval", "motion", "--out", str(tmp_path), "--real", str(tmp_path / "none.tfrecord"),
                                 "--predictor", "smart"])
    assert result.exit_code == 2 and "unknown predictor" in result.output
    result = runner.invoke(app, ["eval", "motion", "--out", str(tmp_path), "--real", str(tmp_path / "none.tfrecord"),
                                 "--predictor", "log"])
    assert result.exit_code == 2 and "does not exist" in result.output


def test_eval_motion_on_the_samples(shared_data: Path, tmp_path: Path) -> None:
    assert len(default_real_logs()) == 3  # the samples beside the repository
    out = tmp_path / "out"
    result = runner.invoke(app, ["eval", "motion", "--out", str(out), "--predictor", "constant-velocity,log",
                                 "--no-real-edits", "--diagnose", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output.strip().splitlines()[-1])
    assert [(r["dataset"], r["method"], r["predictor"]) for r in data["rows"]] == [
        ("waymo-motion", "log", ""), ("waymo-motion", "full", "constant-velocity"), ("av2", "log", ""),
        ("av2", "full", "constant-velocity"), ("av2-forecasting", "log", ""),
        ("av2-forecasting", "full", "constant-velocity")]
    assert [r["scenarios"] for r in data["rows"]] == [1, 1, 7, 7, 2, 2]  # 9.1 s windows 10 steps apart
    table = pq.read_table(out / "tables" / "motion.parquet")
    assert table.num_rows == 6 and (out / "tables" / "motion.md").exists() and (out / "manifest.json").exists()
    assert pq.read_table(out / "tables" / "motion_outcomes.parquet").num_rows == 0  # no edits evaluated
    assert pq.read_table(out / "tables" / "motion_stalls.parquet").num_rows == 0  # constant velocity is not traced


def test_seq_needs_a_store_and_an_aligned_scene(tmp_path: Path) -> None:
    result = runner.invoke(app, ["eval", "motion", "--out", str(tmp_path / "out"), "--seq", "synth-000001"])
    assert result.exit_code == 2 and "--seq needs --store" in result.output
    result = runner.invoke(app, ["eval", "motion", "--out", str(tmp_path / "out"), "--store", str(tmp_path / "s"),
                                 "--seq", "synth-000001"])
    assert result.exit_code == 2 and "no language scene" in result.output
