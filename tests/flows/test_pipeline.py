"""The main flow fans out one task per sequence on Ray, stores complete logs, and skips finished work."""

from __future__ import annotations

import pytest

from flows.pipeline import main_flow
from flows.runtime import RunnerKind, make_task_runner
from simsplat_core.world import WorldConfig
from storage import ArtifactStore, list_logs, read_scene_log
from tests.flows.test_cli import _tree_digest

pytestmark = pytest.mark.orchestration


def test_main_flow_on_ray_generates_then_skips_then_redoes_on_config_change(prefect_api_url, tmp_path):
    config = WorldConfig(num_frames=6, width=80, height=56)
    flow = main_flow.with_options(task_runner=make_task_runner(RunnerKind.ray, 2))

    first = flow(store_root=str(tmp_path), seeds=[1, 2], config=config)
    assert [s.summary.seq_id for s in first] == ["synth-000001", "synth-000002"]
    assert not any(s.skipped for s in first)
    store = ArtifactStore(str(tmp_path))
    assert list_logs(store) == ["synth-000001", "synth-000002"]
    for stored in first:
        log = read_scene_log(store, stored.summary.seq_id)
        assert log.num_frames == 6
        assert stored.summary.num_images == len(log.images) == 6 * len(log.cameras)
        assert stored.bytes_on_disk > 0

    digest = _tree_digest(tmp_path)
    second = flow(store_root=str(tmp_path), seeds=[1, 2], config=config)
    assert all(s.skipped for s in second)
    assert _tree_digest(tmp_path) == digest

    third = flow(store_root=str(tmp_path), seeds=[1], config=WorldConfig(num_frames=7, width=80, height=56))
    assert not third[0].skipped
    assert read_scene_log(store, "synth-000001", load_images=False).num_frames == 7
