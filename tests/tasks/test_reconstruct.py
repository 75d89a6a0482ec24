"""The reconstruct task without orchestration: stores a scene that renders like the trained graph, then skips."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from simsplat_core.scene import ReconstructionConfig, SceneGraph
from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, list_scenes, read_scene, write_scene_log
from tasks.progress import listening
from tasks.reconstruct import reconstruct_scene, scene_hash


@pytest.fixture(scope="module")
def stored_log(tmp_path_factory):
    store = ArtifactStore(tmp_path_factory.mktemp("store"))
    log = generate_log(seed=3, config=WorldConfig(num_frames=4, width=64, height=48, test_every=2), seq_id="s3")
    written = write_scene_log(store, log)
    return store, log, written.key


def test_task_stores_a_scene_that_renders_like_the_trained_graph_then_skips(stored_log, monkeypatch):
    store, log, log_key = stored_log
    config = ReconstructionConfig(iterations=6, progress_every=3)
    trained = {}
    import tasks.reconstruct as module

    real_reconstruct = module.reconstruct

    def keep_result(*args, **kwargs):
        trained["result"] = real_reconstruct(*args, **kwargs)
        return trained["result"]

    monkeypatch.setattr(module, "reconstruct", keep_result)
    reports = []
    with listening(lambda label, step, total, metrics: reports.append((label, step, total))):
        stored = reconstruct_scene.fn(store.root, "s3", config)
    assert reports[-1] == ("reconstruct s3", 6, 6) and len(reports) >= 2
    assert not stored.skipped and stored.scene_hash == scene_hash(log_key, config)
    assert stored.relpath == f"scenes/s3/{stored.scene_hash}" and stored.metrics["iterations"] == 6

    loaded = read_scene(store, "s3")
    assert loaded.scene_hash == stored.scene_hash and loaded.metrics == pytest.approx(stored.metrics, nan_ok=True)
    assert loaded.manifest["provenance"]["log_key"] == log_key
    graph = SceneGraph.from_records(loaded.records)
    original = trained["result"].graph
    cam = log.images_at(1)[0]
    c2w, K = torch.tensor(cam.cam_to_world[None], dtype=torch.float32), torch.tensor(cam.K[None], dtype=torch.float32)
    with torch.no_grad():
        expected = original.render(1, c2w, K, cam.width, cam.height).rgb
        actual = graph.render(1, c2w, K, cam.width, cam.height).rgb
    assert torch.allclose(actual, expected, atol=1e-5)
    test_frames = sorted({(r.camera, r.frame_idx) for r in trained["result"].test_renders})
    assert loaded.manifest["renders"]["files"] == sorted(f"renders/{c}/{f:06d}.exr" for c, f in test_frames)

    again = reconstruct_scene.fn(store.root, "s3", config)
    assert again.skipped and again.scene_hash == stored.scene_hash and again.seconds == 0.0
    assert again.metrics == pytest.approx(stored.metrics, nan_ok=True)
    assert list_scenes(store, "s3") == [stored.scene_hash]


def test_scene_hash_depends_on_log_and_config():
    config = ReconstructionConfig(iterations=6)
    assert scene_hash("a", config) == scene_hash("a", ReconstructionConfig(iterations=6))
    assert scene_hash("a", config) != scene_hash("b", config)
    assert scene_hash("a", config) != scene_hash("a", dataclasses.replace(config, seed=1))


def test_scene_hash_ignores_run_only_settings():
    config = ReconstructionConfig(iterations=6)
    for run_only in (dict(num_threads=1), dict(progress_every=3), dict(eval_every=2)):
        assert scene_hash("a", dataclasses.replace(config, **run_only)) == scene_hash("a", config)


def test_missing_log_is_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="logs/nope: no complete scene log"):
        reconstruct_scene.fn(str(tmp_path), "nope", ReconstructionConfig(iterations=1))
    assert not np.any([p.is_file() for p in tmp_path.rglob("*")])
