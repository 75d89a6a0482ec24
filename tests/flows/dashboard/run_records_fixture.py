"""Run records of the dashboard tests' store: the mining run ``mine-dash`` as a completed main run (its stages per
sequence, the mine stage from the mining summary itself), a running run with a queued, a running and a failed
stage (its page updates live), and a run whose record is garbled."""

from __future__ import annotations

import datetime

from storage import ArtifactStore
from storage.run_records import RunRecord, StageRecord, write_run_record, write_stage_record
from tasks.mine import MiningSummary

LIVE_RUN = "main-live"
GARBLED_RUN = "main-garbled"
FAILED_SEQ = "synth-000009"
FAILURE = "ValueError: synth-000009: frames.parquet has no rows"
START = datetime.datetime(2026, 1, 2, 3, 4, 5, tzinfo=datetime.UTC)


def _at(seconds: float) -> str:
    return (START + datetime.timedelta(seconds=seconds)).isoformat(timespec="microseconds")


def add_run_records(root: str, mining: MiningSummary, seq_id: str) -> None:
    """Write the run records of the module docstring into the store at ``root``."""
    store = ArtifactStore(root)
    run = mining.run_id
    mined_s = float(mining.seconds.get("total", 1.0))
    write_run_record(store, RunRecord(run, "simsplat-main", "completed", _at(0), _at(30 + mined_s), "v0.1-test",
                                      {"seeds": [0], "mining": {"per_sequence": 2, "max_attempts": 2}},
                                      {"logs": 1, "scenes": 1, "language_scenes": 1,
                                       "accepted_scenarios": mining.accepted, "exported": mining.accepted}))
    done = [("ingest", 1.5, 0), ("reconstruct", 12.0, 0), ("align", 6.0, 1), ("mine", mined_s, 0)]
    clock = 0.0
    for stage, seconds, retries in done:
        write_stage_record(store, run, StageRecord(seq_id, stage, "completed", _at(clock + seconds), _at(clock),
                                                   seconds, retries, task=f"{stage}-task"))
        clock += seconds
    write_stage_record(store, run, StageRecord(seq_id, "evaluate", "skipped", _at(clock),
                                               skip_reason="evaluation not requested"))
    write_stage_record(store, run, StageRecord(seq_id, "export", "completed", _at(clock + 1), _at(clock), 1.0, 0))

    now = datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds")
    # a live run's process beats every 30 s; this one stands for a run alive for the whole test session
    beating = (datetime.datetime.now(datetime.UTC) + datetime.timedelta(days=1)).isoformat(timespec="microseconds")
    write_run_record(store, RunRecord(LIVE_RUN, "simsplat-main", "running", now, code_version="v0.1-test",
                                      parameters={"seeds": [0, 9]}, counts={"logs": 2}, heartbeat_at=beating))
    write_stage_record(store, LIVE_RUN, StageRecord(seq_id, "ingest", "completed", now, now, 0.5, 0))
    write_stage_record(store, LIVE_RUN, StageRecord(seq_id, "reconstruct", "running", now, now, retries=0))
    write_stage_record(store, LIVE_RUN, StageRecord(FAILED_SEQ, "ingest", "failed", now, now, 0.2, 1, error=FAILURE))
    write_stage_record(store, LIVE_RUN, StageRecord(FAILED_SEQ, "reconstruct", "skipped", now,
                                                    skip_reason="no camera images"))
    store.write_bytes(f"runs/{GARBLED_RUN}/run.json", b'{"run_id": "main-garbled", "status": ')
