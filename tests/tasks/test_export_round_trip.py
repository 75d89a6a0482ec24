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
