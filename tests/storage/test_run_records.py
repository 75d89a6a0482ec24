"""Run records: a run and its stage events round-trip, the newest event of a stage is its state, and a garbled or
half-written file is reported by name and left out instead of failing the reader."""

from __future__ import annotations

import dataclasses
import datetime

import pytest

from storage import ArtifactStore
from storage.errors import CorruptArtifactError
from storage.run_records import (
    INTERRUPTED,
    PIPELINE_STAGES,
    STALE_AFTER_S,
    RunRecord,
    StageRecord,
    json_safe,
    list_run_ids,
    read_run_record,
    read_stage_matrix,
    read_stage_record,
    stage_record_relpath,
    write_run_record,
    write_stage_record,
)

RUN = "main-20260101T000000000000Z"


def _stage(seq: str, stage: str, status: str, at: str, **kw) -> StageRecord:
    return StageRecord(seq, stage, status, f"2026-01-01T00:00:{at}+00:00", **kw)


def test_run_record_round_trip_and_duration(tmp_path):
    store = ArtifactStore(tmp_path)
    record = RunRecord(RUN, "simsplat-main", "failed", "2026-01-01T00:00:00+00:00", "2026-01-01T00:01:30+00:00",
                       code_version="abc123", parameters={"seeds": [1, 2], "config": {"width": 80}},
                       counts={"logs": 2, "scenes": 1}, error="RuntimeError: boom")
    write_run_record(store, record)
    assert read_run_record(store, RUN) == record
    assert record.seconds() == 90.0
    assert read_run_record(store, "other-run") is None
    assert list_run_ids(store) == [RUN]


def test_stage_matrix_takes_each_stages_newest_event(tmp_path):
    store = ArtifactStore(tmp_path)
    write_stage_record(store, RUN, _stage("synth-000002", "reconstruct", "queued", "01"))
    write_stage_record(store, RUN, _stage("synth-000002", "reconstruct", "running", "02", retries=1))
    write_stage_record(store, RUN, _stage("synth-000002", "reconstruct", "failed", "05", seconds=3.0, retries=1,
                                          error="ValueError: no frames"))
    write_stage_record(store, RUN, _stage("synth-000001", "reconstruct", "completed", "04", seconds=2.5, retries=0))
    write_stage_record(store, RUN, _stage("synth-000001", "evaluate", "skipped", "04",
                                          skip_reason="no ground-truth captions (real log)"))
    matrix = read_stage_matrix(store, RUN)
    assert matrix.seq_ids == ("synth-000001", "synth-000002")
    assert matrix.stages == PIPELINE_STAGES and not matrix.problems
    failed = matrix.cell("synth-000002", "reconstruct")
    assert failed is not None
    assert (failed.status, failed.retries, failed.error) == ("failed", 1, "ValueError: no frames")
    assert matrix.cell("synth-000001", "evaluate").skip_reason == "no ground-truth captions (real log)"
    assert matrix.cell("synth-000001", "align") is None
    assert read_stage_record(store, RUN, "synth-000002", "reconstruct", "running").retries == 1
    # a stage queued again later (a resumed run) shows as queued, not as its older outcome
    write_stage_record(store, RUN, _stage("synth-000002", "reconstruct", "queued", "09"))
    assert read_stage_matrix(store, RUN).cell("synth-000002", "reconstruct").status == "queued"


def test_garbled_and_half_written_stage_files_are_reported_not_fatal(tmp_path):
    store = ArtifactStore(tmp_path)
    write_stage_record(store, RUN, _stage("synth-000001", "ingest", "completed", "01", seconds=1.0))
    garbled = stage_record_relpath(RUN, "synth-000001", "align", "completed")
    store.write_bytes(garbled, b'{"seq_id": "synth-000001", "sta')
    wrong = stage_record_relpath(RUN, "synth-000003", "mine", "failed")
    store.write_json(wrong, {"seq_id": "synth-000003", "stage": "mine", "status": "exploded", "recorded_at": "x"})
    store.write_bytes(stage_record_relpath(RUN, "synth-000001", "mine", "running") + ".tmp-0123", b"{")
    matrix = read_stage_matrix(store, RUN)
    assert matrix.seq_ids == ("synth-000001",)
    assert matrix.cell("synth-000001", "ingest").status == "completed"
    assert len(matrix.problems) == 2
    assert any("align-completed.json" in p and "not valid JSON" in p for p in matrix.problems)
    assert any("mine-failed.json" in p and "exploded" in p for p in matrix.problems)


def test_garbled_run_record_names_the_file_and_field(tmp_path):
    store = ArtifactStore(tmp_path)
    store.write_bytes(f"runs/{RUN}/run.json", b"{not json")
    with pytest.raises(CorruptArtifactError, match="run.json"):
        read_run_record(store, RUN)
    store.write_json(f"runs/{RUN}/run.json", {"run_id": RUN, "flow": "f", "status": "running"})
    with pytest.raises(CorruptArtifactError, match="started_at"):
        read_run_record(store, RUN)
    store.write_json(f"runs/{RUN}/run.json", {"run_id": "elsewhere", "flow": "f", "status": "running",
                                              "started_at": "2026-01-01T00:00:00+00:00"})
    with pytest.raises(CorruptArtifactError, match="elsewhere"):
        read_run_record(store, RUN)


def test_records_refuse_bad_values():
    with pytest.raises(ValueError, match="stage status"):
        StageRecord("synth-000001", "align", "done", "2026-01-01T00:00:00+00:00")
    with pytest.raises(ValueError, match="sequence id"):
        StageRecord("../etc", "align", "queued", "2026-01-01T00:00:00+00:00")
    with pytest.raises(ValueError, match="retries"):
        StageRecord("synth-000001", "align", "completed", "2026-01-01T00:00:00+00:00", retries=-1)


def test_json_safe_turns_configs_into_plain_json():
    from pathlib import PurePosixPath

    from simsplat_core.world import WorldConfig

    safe = json_safe({"config": WorldConfig(num_frames=6), "seeds": (1, 2), "nan": float("nan"),
                      "path": PurePosixPath("/data/store")})
    assert safe["config"]["num_frames"] == 6 and safe["seeds"] == [1, 2] and safe["nan"] is None
    assert safe["path"] == "/data/store"


def test_a_running_record_whose_heartbeat_stopped_reads_as_interrupted():
    beat = datetime.datetime(2026, 1, 1, 12, 0, tzinfo=datetime.UTC)
    record = RunRecord("run-1", "simsplat-main", "running", (beat - datetime.timedelta(minutes=5)).isoformat(),
                       heartbeat_at=beat.isoformat())
    fresh, stale = (beat + datetime.timedelta(seconds=STALE_AFTER_S * f) for f in (0.5, 1.5))
    assert record.observed_status(fresh) == "running" and record.seconds(fresh) == 300 + STALE_AFTER_S * 0.5
    assert record.observed_status(stale) == INTERRUPTED and record.seconds(stale) == 300  # up to the last heartbeat
    done = dataclasses.replace(record, status="completed", finished_at=beat.isoformat())
    assert done.observed_status(stale) == "completed"

