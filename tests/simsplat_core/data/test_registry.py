"""The log-source registry: names, detection of each kind of log, dispatch, landing-folder scan."""

from __future__ import annotations

from pathlib import Path

import pytest

from simsplat_core.data import CorruptLogError
from simsplat_core.data.registry import (
    AUTO_SOURCE,
    LOG_SOURCES,
    UnknownLogSourceError,
    detect_source,
    find_logs,
    load_log,
    log_source,
    resolve_source,
    source_names,
)
from simsplat_core.data.tfrecord import encode_tfrecord
from tests.simsplat_core.data.forecasting_files import SCENARIO_ID, write_scenario


def test_sources_are_registered_once_with_descriptions() -> None:
    assert source_names() == ("waymo-frame", "waymo-scenario", "av2", "av2-forecasting", "kitti-raw", "dgp")
    assert AUTO_SOURCE not in source_names()
    assert all(s.description and callable(s.detect) and callable(s.load) for s in LOG_SOURCES)
    assert log_source("waymo-frame").options == ("image_scale",) and log_source("av2").options == ()


def test_unknown_source_lists_the_known_ones(tmp_path: Path) -> None:
    with pytest.raises(UnknownLogSourceError, match="unknown log source 'kitti'") as info:
        log_source("kitti")
    assert all(f"{name}: " in str(info.value) for name in source_names())
    junk = tmp_path / "notes.txt"
    junk.write_text("hello")
    assert detect_source(junk) is None and detect_source(tmp_path) is None
    with pytest.raises(UnknownLogSourceError, match="no log source recognises it") as info:
        resolve_source(AUTO_SOURCE, junk)
    assert "av2-forecasting: " in str(info.value)


def test_detection_reads_content_not_names(tmp_path: Path) -> None:
    folder = write_scenario(tmp_path / "landing" / "a")
    assert detect_source(folder) == "av2-forecasting"
    assert detect_source(folder / f"scenario_{SCENARIO_ID}.parquet") == "av2-forecasting"
    fake = tmp_path / "scenario_fake.parquet"  # the name alone is not enough
    fake.write_bytes(b"PAR1 not really")
    assert detect_source(fake) is None
    record = tmp_path / "other.tfrecord"  # a valid TFRecord whose record is neither a Frame nor a Scenario
    record.write_bytes(encode_tfrecord(b"\x0a\x03abc"))
    assert detect_source(record) is None


def test_dispatch_and_options(tmp_path: Path) -> None:
    folder = write_scenario(tmp_path / "s")
    log = load_log(AUTO_SOURCE, folder, seq_id="mine")
    assert (log.source, log.seq_id) == ("av2-forecasting", "mine")
    with pytest.raises(TypeError, match="'av2-forecasting' takes no option 'image_scale'"):
        load_log("av2-forecasting", folder, image_scale=0.5)
    with pytest.raises(CorruptLogError, match="no log_map_archive"):  # the named loader's own error
        load_log("av2-forecasting", write_scenario(tmp_path / "no-map", archive={}))


def test_landing_folder_scan(tmp_path: Path) -> None:
    landing = tmp_path / "landing"
    write_scenario(landing / "day1" / "a")
    write_scenario(landing / "day2" / "b", scenario_id="second")
    (landing / "day2" / "readme.txt").write_text("not a log")
    write_scenario(landing / ".partial" / "c")  # hidden: still arriving
    found = list(find_logs(landing))
    assert found == [("av2-forecasting", landing / "day1" / "a"), ("av2-forecasting", landing / "day2" / "b")]


SAMPLES = {
    "waymo/pvps_data_one_frame.tfrecord": "waymo-frame",
    "waymo/motion_data_one_scenario.tfrecord": "waymo-scenario",
    "av2/sensor-log-7fab2350": "av2",
    "av2/forecasting-0a1e6f0a": "av2-forecasting",
    "av2/forecasting-0a1e6f0a/scenario_0a1e6f0a-1817-4a98-b02e-db8c9327d151.parquet": "av2-forecasting",
    "kitti/KITTI_tiny/2011_09_26/2011_09_26_drive_0023_sync": "kitti-raw",
}


@pytest.mark.shared_data
@pytest.mark.parametrize(("sample", "source"), SAMPLES.items())
def test_each_sample_is_detected(shared_data: Path, sample: str, source: str) -> None:
    assert detect_source(shared_data / sample) == source


@pytest.mark.shared_data
def test_scan_of_the_samples(shared_data: Path) -> None:
    found = [(source, path.relative_to(shared_data).as_posix()) for source, path in find_logs(shared_data / "av2")]
    assert found == [("av2-forecasting", "av2/forecasting-0a1e6f0a"), ("av2", "av2/sensor-log-7fab2350")]
    assert [s for s, _ in find_logs(shared_data / "waymo")] == ["waymo-scenario", "waymo-frame"]
