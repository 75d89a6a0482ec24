"""``simsplat ingest SOURCE PATH``: sources from the registry, ``auto`` detection, options per source."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flows.cli import app
from storage import ArtifactStore, list_logs, read_scene_log
from tests.simsplat_core.data.forecasting_files import SCENARIO_ID, write_scenario

runner = CliRunner()


def _text(output: str) -> str:
    """The CLI output with the error box's borders and line wrapping removed."""
    return " ".join(output.replace("│", " ").split())


def test_unknown_source_lists_the_registry(tmp_path: Path) -> None:
    result = runner.invoke(app, ["ingest", "kitti", str(tmp_path), "--out", str(tmp_path / "store")])
    assert result.exit_code != 0
    for name in ("waymo-frame", "waymo-scenario", "av2", "av2-forecasting"):
        assert name in result.output
    assert not (tmp_path / "store").exists()


def test_auto_and_options_are_checked_before_any_work(tmp_path: Path) -> None:
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"\x00" * 64)
    result = runner.invoke(app, ["ingest", "auto", str(junk), "--out", str(tmp_path / "store")])
    assert result.exit_code != 0 and "no log source recognises it" in _text(result.output)
    folder = write_scenario(tmp_path / "s")
    result = runner.invoke(app, ["ingest", "av2-forecasting", str(folder), "--out", str(tmp_path / "store"),
                                 "--image-scale", "0.5"])
    assert result.exit_code != 0 and "no camera images to scale" in _text(result.output)
    result = runner.invoke(app, ["ingest", "av2", str(tmp_path / "missing"), "--out", str(tmp_path / "store")])
    assert result.exit_code != 0 and "does not exist" in _text(result.output)


@pytest.mark.orchestration
def test_ingest_auto_detects_a_forecasting_scenario(prefect_api_url, tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    folder = write_scenario(tmp_path / "landing" / "scenario")
    result = runner.invoke(app, ["ingest", "auto", str(folder), "--out", store.root])
    assert result.exit_code == 0, result.output
    assert list_logs(store) == [SCENARIO_ID]
    log = read_scene_log(store, SCENARIO_ID)
    assert log.source == "av2-forecasting" and log.num_frames == 20 and len(log.tracks) == 3


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_ingest_kitti_raw_stores_cameras_poses_and_sparse_depth(prefect_api_url, shared_data: Path,
                                                               tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    drive = shared_data / "kitti/KITTI_tiny/2011_09_26/2011_09_26_drive_0023_sync"
    result = runner.invoke(app, ["ingest", "kitti-raw", str(drive), "--out", store.root, "--image-scale", "0.25"])
    assert result.exit_code == 0, result.output
    log = read_scene_log(store, "2011_09_26_drive_0023_sync")
    assert log.source == "kitti-raw" and log.num_frames == 7 and not log.tracks
    assert log.cameras == ("image_02", "image_03") and len(log.images) == 14
    assert {img.frame_idx for img in log.images if img.split == "test"} == {3}
    depth = log.images[0].depth
    assert depth is not None and np.isnan(depth).any() and (np.isfinite(depth) & (depth > 0)).any()
