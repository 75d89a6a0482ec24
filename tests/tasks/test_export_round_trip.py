"""Real samples out and back in: a stored log exported as WOMD shards re-ingests as the same scenario."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data.waymo_scenario import load_waymo_scenario
from simsplat_core.export.windows import ExportLayout
from simsplat_core.geometry import wrap_angle
from simsplat_core.types import SceneLog
from storage import ArtifactStore, read_scene_log
from tasks.export import ExportConfig, export_dataset
from tasks.export_inputs import ExportFilters
from tasks.logs import ingest_real_log

pytestmark = pytest.mark.shared_data


def _round_trip(tmp_path: Path, source: str, path: Path, layout: ExportLayout) -> tuple[SceneLog, SceneLog, dict]:
    """Ingest ``path``, export it unedited as WOMD (one window of ``layout``), re-ingest the shard."""
    store_root = str(tmp_path / "store")
    stored = ingest_real_log.fn(store_root, source, str(path))
    config = ExportConfig(name="rt", formats=("womd",), filters=ExportFilters(include="logs"), layout=layout,
                          splits=(("train", 1.0),))
    result = export_dataset(store_root, str(tmp_path / "out"), config)
    (shard,) = result.shards
    manifest = json.loads((tmp_path / "out" / "rt" / "manifest.json").read_text())
    original = read_scene_log(ArtifactStore(store_root), stored.summary.seq_id, load_images=False)
    return original, load_waymo_scenario(tmp_path / "out" / "rt" / shard.path), manifest


def _same_tracks(original: SceneLog, back: SceneLog, manifest: dict) -> None:
    (entry,) = manifest["scenarios"].values()
    ids = entry["track_ids"]
    assert int(back.metadata["sdc_track_id"]) == ids["ego"]
    np.testing.assert_allclose(back.ego_poses[:, :3, 3], original.ego_poses[:, :3, 3], atol=0.01)
    by_id = {t.object_id: t for t in back.tracks}
    assert len(back.tracks) == len(original.tracks)
    for track in original.tracks:
        again = by_id[str(ids[track.object_id])]
        np.testing.assert_array_equal(again.frame_idx, track.frame_idx)  # validity identical
        np.testing.assert_allclose(again.center, track.center, atol=0.01)
        np.testing.assert_allclose(wrap_angle(again.heading - track.heading), 0.0, atol=1e-3)
        np.testing.assert_allclose(again.size, track.size, atol=1e-3)


def _kinds(log: SceneLog) -> Counter[str]:
    kinds = Counter(f.kind for f in log.map_features)
    for extra in ("stop_signs", "speed_bumps"):
        kinds[extra] = len(json.loads(log.metadata.get(extra, "[]")))
    return kinds


def test_waymo_motion_sample_round_trip(shared_data: Path, tmp_path: Path) -> None:
    original, back, manifest = _round_trip(tmp_path, "waymo-scenario",
                                           shared_data / "waymo" / "motion_data_one_scenario.tfrecord", ExportLayout())
    _same_tracks(original, back, manifest)
    assert original.metadata["sdc_track_id"] == back.metadata["sdc_track_id"]  # the source's ids survive
    assert _kinds(back) == _kinds(original)
    assert json.loads(back.metadata["tracks_to_predict"]) == json.loads(original.metadata["tracks_to_predict"])
    signals = json.loads(back.metadata["traffic_signals"])
    assert [len(step) for step in signals] == [len(step) for step in json.loads(original.metadata["traffic_signals"])]


def test_av2_forecasting_sample_round_trip(shared_data: Path, tmp_path: Path) -> None:
    layout = ExportLayout(steps=110, current_index=49)  # the sample's own 11 s at 10 Hz, one window
    original, back, manifest = _round_trip(tmp_path, "av2-forecasting", shared_data / "av2" / "forecasting-0a1e6f0a",
                                           layout)
    _same_tracks(original, back, manifest)
    kinds, again = _kinds(original), _kinds(back)
    assert again["lane"] == kinds["lane"] and again["crosswalk"] == kinds["crosswalk"]
    assert again["road_edge"] == kinds["road_edge"]


def test_av2_forecasting_edit_exports_and_reingests(shared_data: Path, tmp_path: Path) -> None:
    """A stopped truck put into the AV2 forecasting sample (aligned from its tracks, no images) comes back from its
    WOMD export standing where it was put; braking "the lead vehicle" is refused, as the sample has none moving."""
    from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
    from tasks.align import align_scene, train_motion_aligner
    from tasks.edit import run_edit
    from tasks.stored_edits import load_edit_context

    root = str(tmp_path / "store")
    seq = ingest_real_log.fn(root, "av2-forecasting", str(shared_data / "av2" / "forecasting-0a1e6f0a")).summary.seq_id
    model = train_motion_aligner.fn(root, [seq], MotionAlignerConfig(epochs=20))
    align_scene.fn(root, seq, None, model.model_hash)
    loaded = load_edit_context(root, seq)
    brake = run_edit(root, seq, "the lead vehicle brakes hard", run_id="av2", loaded=loaded)
    assert brake.status == "refused" and "no lead vehicle" in brake.message
    truck = run_edit(root, seq, "insert a stopped truck in the ego lane 30 m ahead", run_id="av2", loaded=loaded)
    assert truck.status == "succeeded" and truck.edited is not None and truck.edited.validation.ok
    config = ExportConfig(name="av2", formats=("womd", "scenarionet", "parquet"), splits=(("train", 1.0),),
                          filters=ExportFilters(include="all-edits"), layout=ExportLayout(steps=110, current_index=49))
    result = export_dataset(root, str(tmp_path / "out"), config)
    assert result.written == 1 and not result.left_out
    (womd_shard,) = [s for s in result.shards if s.format == "womd"]
    back = load_waymo_scenario(tmp_path / "out" / "av2" / womd_shard.path)
    (entry,) = json.loads((tmp_path / "out" / "av2" / "manifest.json").read_text())["scenarios"].values()
    original = read_scene_log(ArtifactStore(root), seq, load_images=False)
    (added,) = [o for o in entry["track_ids"] if o != "ego" and o not in {t.object_id for t in original.tracks}]
    stands = {t.object_id: t for t in back.tracks}[str(entry["track_ids"][added])]
    assert np.abs(stands.center - stands.center[0]).max() < 0.05 and stands.size[0, 0] > 6.0
    assert json.loads(back.metadata["objects_of_interest"]) == [entry["track_ids"][added]]
