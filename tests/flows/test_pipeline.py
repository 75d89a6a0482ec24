"""The main flow fans out one task per sequence on Ray, stores complete logs and scenes, and skips finished work."""

from __future__ import annotations

import dataclasses
import socket

import pytest

from flows.pipeline import (
    ExportPlan,
    MainResult,
    MiningPlan,
    idle_main_run,
    main_flow,
    reconstruction_config,
    scheduled_main_flow,
)
from flows.runtime import RunnerKind, make_task_runner
from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import AlignmentConfig
from simsplat_core.world import WorldConfig
from storage import ArtifactStore, list_logs, list_scenes, read_scene, read_scene_log
from storage.assets import list_asset_banks
from storage.edits import read_edit_records
from storage.language_scenes import list_language_scenes, read_language_scene
from storage.run_records import list_run_ids, read_run_record, read_stage_matrix
from tests.flows.test_cli import _tree_digest

pytestmark = pytest.mark.orchestration

#: Tiny: 6 frames at 80x56, frames 2 and 5 held out for test; 30 reconstruction iterations.
WORLD = WorldConfig(num_frames=6, width=80, height=56, test_every=3)
RECON = reconstruction_config(30)
ALIGN = dict(alignment=AlignmentConfig(fit_iterations=3, autoencoder_steps=50, eval_views=0, min_area=10, small_area=4),
             aligner=MotionAlignerConfig(epochs=3))


def test_main_flow_on_ray_generates_and_reconstructs_then_skips_then_redoes_on_config_change(prefect_api_url, tmp_path,
                                                                                            monkeypatch):
    flow = main_flow.with_options(task_runner=make_task_runner(RunnerKind.ray, 2))

    first = flow(store_root=str(tmp_path), seeds=[1, 2], config=WORLD, reconstruction=RECON, **ALIGN)
    assert [s.summary.seq_id for s in first.logs] == ["synth-000001", "synth-000002"]
    assert [s.seq_id for s in first.scenes] == ["synth-000001", "synth-000002"]
    assert not any(s.skipped for s in first.logs + first.scenes)
    store = ArtifactStore(str(tmp_path))
    assert list_logs(store) == ["synth-000001", "synth-000002"]
    for stored in first.logs:
        log = read_scene_log(store, stored.summary.seq_id)
        assert log.num_frames == 6
        assert stored.summary.num_images == len(log.images) == 6 * len(log.cameras)
        assert stored.bytes_on_disk > 0
    for scene in first.scenes:
        loaded = read_scene(store, scene.seq_id)
        assert loaded.scene_hash == scene.scene_hash and loaded.metrics == scene.metrics
        assert scene.metrics["iterations"] == 30 and scene.metrics["psnr_test"] > 5.0
        assert len(loaded.records.gaussians["mean"]) == scene.metrics["num_gaussians"]
        renders = sorted(p for p in store.walk(f"{scene.relpath}/renders"))
        assert renders == sorted(f"{cam}/{f:06d}.exr" for cam in log.cameras for f in (2, 5))
    # language alignment: one aligner trained on both logs, one language scene per reconstructed scene
    assert (
        first.aligner is not None
        and not first.aligner.skipped
        and first.aligner.seq_ids == ("synth-000001", "synth-000002")
    )
    for scene, language in zip(first.scenes, first.language):
        assert (language.seq_id, language.scene_hash, language.model_hash) == (scene.seq_id, scene.scene_hash,
                                                                               first.aligner.model_hash)
        lang = read_language_scene(store, scene.seq_id).scene
        assert lang.scene_hash == scene.scene_hash and lang.node_id_maps.shape[0] == 6
        assert any(n.motion is not None for n in lang.nodes)
    # grounding evaluation: the run's tables
    assert first.grounding is not None and first.grounding.queries > 0
    assert set(first.grounding.tables) == {"grounding", "grounding_ablation", "grounding_outcomes"}
    assert store.exists(f"runs/{first.run_id}/tables/grounding.parquet")
    assert store.exists(f"runs/{first.run_id}/tables/grounding.md")
    assert 0.0 <= first.grounding.scores["ours"]["total"]["acc"] <= 1.0
    _check_run_record(store, first.run_id, first)

    digest = _artifact_digest(tmp_path)
    second = flow(store_root=str(tmp_path), seeds=[1, 2], config=WORLD, reconstruction=RECON, evaluate=False, **ALIGN)
    assert all(s.skipped for s in second.logs + second.scenes + second.language) and second.aligner.skipped
    assert [s.metrics for s in second.scenes] == [s.metrics for s in first.scenes]
    assert _artifact_digest(tmp_path) == digest  # only the second run's own record is new
    reused = read_stage_matrix(store, second.run_id)  # stored work reused, evaluation not asked for
    assert all("reused" in reused.cell(seq, "align").note and reused.cell(seq, "evaluate") is None
               for seq in reused.seq_ids)

    # mining: the asset bank is built first, then one mining task per aligned sequence; every attempt is a row of
    # the run's edits table, stored logs and scenes are reused
    mined = flow(store_root=str(tmp_path), seeds=[1, 2], config=WORLD, reconstruction=RECON, evaluate=False,
                 mining=MiningPlan(per_sequence=1, max_attempts=1), run_id="mined",
                 export=ExportPlan(out=str(tmp_path / "exported")), **ALIGN)
    assert all(s.skipped for s in mined.logs + mined.scenes + mined.language)
    assert list_asset_banks(store) and [m.seq_id for m in mined.mining] == ["synth-000001", "synth-000002"]
    rows = read_edit_records(store, "mined")
    assert len(rows) == sum(m.attempts for m in mined.mining) >= 2
    assert {r.seq_id for r in rows} == {"synth-000001", "synth-000002"}
    assert sum(r.export for r in rows) == sum(m.accepted for m in mined.mining)
    # export: the run's accepted scenarios as a dataset named after the run (none accepted: no export)
    accepted = sum(m.accepted for m in mined.mining)
    assert (mined.export is not None) == (accepted > 0)
    if mined.export is not None:
        assert mined.export.written + len(mined.export.left_out) == accepted
        assert (tmp_path / "exported" / "mined" / "manifest.json").is_file()
        assert store.exists("datasets/mined.json")
    _check_mined_record(store, mined)
    _check_mined_once(tmp_path, store, mined)
    _mine_with_the_vlm_down(store, monkeypatch)

    changed_world = WorldConfig(num_frames=7, width=80, height=56, test_every=3)
    third = flow(store_root=str(tmp_path), seeds=[1], config=changed_world, reconstruction=reconstruction_config(20),
                 align=False)
    assert third.aligner is None and third.language == []
    assert len(list_language_scenes(store, "synth-000001")) == 1  # the earlier one stays
    assert not third.logs[0].skipped and not third.scenes[0].skipped
    assert read_scene_log(store, "synth-000001", load_images=False).num_frames == 7
    assert list_scenes(store, "synth-000001") == [first.scenes[0].scene_hash, third.scenes[0].scene_hash]
    newest = read_scene(store, "synth-000001")
    assert newest.scene_hash == third.scenes[0].scene_hash and newest.metrics["iterations"] == 20


def _check_mined_once(tmp_path, store, mined) -> None:
    """The same mining again mines nothing (the mining ledger has both sequences: the record says by which run);
    with nothing new at all (the synthetic sequences asked stored alike) the run is recorded without a flow; another
    mining seed or K, or other world settings, is work to do."""
    mining = MiningPlan(per_sequence=1, max_attempts=1)
    flow = main_flow.with_options(task_runner=make_task_runner(RunnerKind.threads, 2))
    again = flow(store_root=str(tmp_path), seeds=[1, 2], config=WORLD, reconstruction=RECON, evaluate=False,
                 mining=mining, run_id="mined-again", export=ExportPlan(out=str(tmp_path / "exported")), **ALIGN)
    assert again.mining == [] and again.export is None and not store.exists("edits/mined-again")
    accepted = {m.seq_id: m.accepted for m in mined.mining}
    matrix = read_stage_matrix(store, "mined-again")
    for seq, n in accepted.items():
        assert matrix.cell(seq, "mine").skip_reason.startswith(f"mined by run mined with these settings ({n} accepted")
        assert matrix.cell(seq, "export").skip_reason == "no new scenario (mined by run mined)"

    params = dict(store_root=str(tmp_path), seeds=[1, 2], config=WORLD, reconstruction=RECON, evaluate=False,
                  mining=mining, **ALIGN)
    idle = idle_main_run(params)
    assert idle is not None and [s.seq_id for s in idle.language] == list(accepted)
    record = read_run_record(store, idle.run_id)
    assert record.status == "completed" and record.counts["mined_before"] == 2 and record.counts["logs"] == 2
    matrix = read_stage_matrix(store, idle.run_id)
    assert all(matrix.cell(seq, stage).status == "skipped" for seq in accepted for stage in ("reconstruct", "align",
                                                                                              "mine"))
    assert all(matrix.cell(seq, "mine").skip_reason.startswith("mined by run mined") for seq in accepted)
    runs = set(list_run_ids(store))
    for changed in (dataclasses.replace(mining, seed=3), dataclasses.replace(mining, per_sequence=2)):
        assert idle_main_run({**params, "mining": changed}) is None
    assert idle_main_run({**params, "config": dataclasses.replace(WORLD, num_frames=7)}) is None
    assert set(list_run_ids(store)) == runs  # a run with work to do is left to the flow, not recorded here


def _mine_with_the_vlm_down(store, monkeypatch) -> None:
    """A mining run with the VLM endpoint down (a closed port of 127.0.0.1; threads, so the tasks see this process's
    environment): every attempt failed naming the connection error, nothing accepted or exported, the run
    completes."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]  # closed when the block ends: nothing listens there
    monkeypatch.setenv("SIMSPLAT_VLM_URL", f"http://127.0.0.1:{port}/v1")
    monkeypatch.setenv("SIMSPLAT_VLM_MODEL", "test-vlm")
    flow = main_flow.with_options(task_runner=make_task_runner(RunnerKind.threads, 2))
    down = flow(store_root=store.root, seeds=[1, 2], config=WORLD, reconstruction=RECON, evaluate=False,
                mining=MiningPlan(per_sequence=1, max_attempts=1, vlm="openai"), run_id="vlm-down",
                export=ExportPlan(out=store.uri("exported")), **ALIGN)
    assert [m.accepted for m in down.mining] == [0, 0] and down.export is None
    rows = read_edit_records(store, "vlm-down")
    assert {r.seq_id for r in rows} == {"synth-000001", "synth-000002"}
    for row in rows:
        assert row.mining["mining_status"] == "failed" and not row.export
        assert "VLMUnreachableError" in row.failure_reason and f"127.0.0.1:{port}" in row.failure_reason
    assert read_run_record(store, "vlm-down").status == "completed" and not store.exists("edits/vlm-down/synth-000001")
    monkeypatch.delenv("SIMSPLAT_VLM_URL")
    monkeypatch.delenv("SIMSPLAT_VLM_MODEL")


def _artifact_digest(root) -> dict[str, str]:
    """``_tree_digest`` without the run records (every flow run writes its own)."""
    return {path: digest for path, digest in _tree_digest(root).items() if not path.startswith("runs/")
            or "/tables/" in path or path.endswith("manifest.json")}


def _check_run_record(store, run_id, result) -> None:
    """The main flow's run record: completed, its parameters, counts and a completed stage per sequence, each
    attempt counted by the task run itself (``retries`` 0: read from Prefect's run count, not left unknown)."""
    record = read_run_record(store, run_id)
    assert (record.flow, record.status, record.error) == ("simsplat-main", "completed", "")
    assert record.finished_at is not None and record.code_version
    assert record.parameters["seeds"] == [1, 2] and record.parameters["config"]["num_frames"] == 6
    assert record.counts == {"logs": 2, "scenes": 2, "language_scenes": 2, "accepted_scenarios": 0}
    matrix = read_stage_matrix(store, run_id)
    assert matrix.seq_ids == tuple(s.summary.seq_id for s in result.logs) and not matrix.problems
    for seq in matrix.seq_ids:
        for stage in ("ingest", "reconstruct", "align", "evaluate"):
            cell = matrix.cell(seq, stage)
            assert (cell.status, cell.retries, cell.error) == ("completed", 0, ""), (seq, stage, cell)
            assert cell.seconds is not None and cell.started_at is not None
        assert matrix.cell(seq, "mine") is None and matrix.cell(seq, "export") is None  # not asked for
    assert "one task for 2 sequences" in matrix.cell(matrix.seq_ids[0], "evaluate").note


def _check_mined_record(store, mined) -> None:
    """The mining run's record: its accepted and exported counts, each sequence mined, exported when it had an
    accepted scenario and skipped (with its reason) otherwise."""
    accepted = sum(m.accepted for m in mined.mining)
    record = read_run_record(store, "mined")
    assert record.counts["accepted_scenarios"] == accepted
    assert record.counts.get("exported", 0) == (mined.export.written if mined.export else 0)
    matrix = read_stage_matrix(store, "mined")
    assert [matrix.cell(seq, "mine").status for seq in matrix.seq_ids] == ["completed", "completed"]
    by_seq = {m.seq_id: m.accepted for m in mined.mining}
    assert {seq: matrix.cell(seq, "export").status for seq in matrix.seq_ids} == {
        seq: "completed" if n else "skipped" for seq, n in by_seq.items()}


def test_the_scheduled_run_with_nothing_new_starts_no_task_runner(monkeypatch, tmp_path):
    """The deployment's flow asks ``idle_main_run`` first; an idle run is returned as recorded, no Ray started."""
    idle, asked = MainResult([], [], run_id="idle"), []
    monkeypatch.setattr("flows.pipeline.idle_main_run", lambda params: asked.append(params) or idle)
    monkeypatch.setattr("flows.runtime.make_task_runner", _no_task_runner)
    assert scheduled_main_flow.fn(str(tmp_path), sequences=0, landing=str(tmp_path), mine=2, seed=4) is idle
    (params,) = asked
    assert (params["seeds"], params["landing"], params["mining"]) == ([], str(tmp_path), MiningPlan(2, seed=4))


def _no_task_runner(*args, **kwargs):
    raise AssertionError("a scheduled run with nothing new built a task runner")
