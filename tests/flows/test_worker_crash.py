"""A Ray worker killed in the middle of a stage: the flow resubmits the task after the retry policy's back-off, the
run completes with every sequence's stage done once, and the run record shows the retry."""

from __future__ import annotations

import datetime

import pytest

import flows.pipeline
from flows.pipeline import main_flow, reconstruction_config
from flows.runtime import RunnerKind, make_task_runner
from simsplat_core.world import WorldConfig
from storage import ArtifactStore, list_scenes, read_scene
from storage.run_records import parse_time, read_run_record, read_stage_matrix
from storage.store import TMP_TAG
from tasks.reconstruct import reconstruct_scene
from tasks.retry_policy import STAGE_RETRIES
from tests.flows.worker_crash import crashing_once

pytestmark = pytest.mark.orchestration

WORLD = WorldConfig(num_frames=6, width=64, height=48, test_every=3)
SEQS = ("synth-000001", "synth-000002")


def test_a_worker_killed_mid_reconstruction_is_resubmitted_and_every_scene_is_stored_once(prefect_api_url, tmp_path,
                                                                                       monkeypatch):
    hooks = tmp_path / "hooks"
    monkeypatch.setattr(flows.pipeline, "reconstruct_scene", crashing_once(reconstruct_scene, SEQS[0], hooks))
    store_root = tmp_path / "store"
    flow = main_flow.with_options(task_runner=make_task_runner(RunnerKind.ray, 2))

    result = flow(store_root=str(store_root), seeds=[1, 2], config=WORLD, reconstruction=reconstruction_config(20),
                  align=False, evaluate=False, run_id="crashed-worker")

    assert (hooks / "crashed").exists()  # the worker did die, while committing the scene
    attempts = sorted(p.name.split(".")[0] for p in (hooks / "attempts").iterdir())
    assert attempts == [SEQS[0], SEQS[0], SEQS[1]]
    assert [s.seq_id for s in result.scenes] == list(SEQS) and not any(s.skipped for s in result.scenes)
    store = ArtifactStore(store_root)
    for scene in result.scenes:
        assert list_scenes(store, scene.seq_id) == [scene.scene_hash]
        assert read_scene(store, scene.seq_id).scene_hash == scene.scene_hash
    leftovers = [p for p in store.walk("scenes") if TMP_TAG in p]
    # the killed commit's staging folder is left behind, hidden, and was never read
    assert leftovers and all(p.split("/")[1].startswith(".") for p in leftovers)

    record = read_run_record(store, "crashed-worker")
    assert record.status == "completed" and record.counts["scenes"] == 2
    matrix = read_stage_matrix(store, "crashed-worker")
    crashed, other = matrix.cell(SEQS[0], "reconstruct"), matrix.cell(SEQS[1], "reconstruct")
    assert (crashed.status, crashed.retries) == ("completed", 1) and "worker crash" in crashed.note
    assert (other.status, other.retries) == ("completed", 0)
    resubmitted = parse_time(crashed.started_at)
    killed = datetime.datetime.fromtimestamp((hooks / "crashed").stat().st_mtime, datetime.UTC)
    low = STAGE_RETRIES.first_delay_s * (1 - STAGE_RETRIES.jitter)
    assert resubmitted - killed >= datetime.timedelta(seconds=low)  # the back-off was waited out
