"""The landing location: new logs ingested once, unchanged ones skipped without decoding, bad ones quarantined."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from storage import ArtifactStore, list_logs, log_dir
from storage.landing import list_quarantined, read_quarantine
from tasks.landing import LandingPlan, check_landing, ingest_landing_log, landing_folder, landing_key, scan_landing
from tests.tasks.landing_files import AV2_FORECASTING, bad_scenario, make_landing


@pytest.fixture
def landing(shared_data: Path, tmp_path: Path) -> Path:
    return make_landing(shared_data, tmp_path / "landing")


def _land_all(store_root: str, plan: LandingPlan) -> None:
    for log in plan.new:
        ingest_landing_log(store_root, log)


def _stored_mtimes(store: ArtifactStore) -> dict[str, int]:
    root = Path(store.root)
    return {seq_id: (root / log_dir(seq_id) / "_SUCCESS.json").stat().st_mtime_ns for seq_id in list_logs(store)}


@pytest.mark.shared_data
def test_first_scan_ingests_the_good_logs_and_quarantines_the_bad_one(landing: Path, tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    plan = scan_landing(store.root, str(landing))
    assert sorted(Path(log.path).name for log in plan.new) == ["broken", "forecasting", "motion.tfrecord"]
    assert plan.already == () and plan.quarantined_known == ()
    outcomes = {Path(log.path).name: ingest_landing_log(store.root, log) for log in plan.new}
    assert outcomes["broken"].stored is None and "position_x" in outcomes["broken"].error
    sources = {name: o.stored.summary.source for name, o in outcomes.items() if o.stored is not None}
    assert sources == {"forecasting": "av2-forecasting", "motion.tfrecord": "waymo-scenario"}
    assert len(list_logs(store)) == 2
    (record,) = list_quarantined(store)
    assert record.path == str(landing / "broken") and record.source == "av2-forecasting"
    assert record.error.startswith("CorruptLogError") and record.first_seen == record.last_tried


@pytest.mark.shared_data
def test_second_scan_finds_nothing_new_and_rewrites_nothing(landing: Path, tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    _land_all(store.root, scan_landing(store.root, str(landing)))
    before = _stored_mtimes(store)
    again = scan_landing(store.root, str(landing))
    assert again.new == ()
    assert sorted(seq_id for _, seq_id in again.already) == sorted(before)
    assert [Path(log.path).name for log, _ in again.quarantined_known] == ["broken"]
    _land_all(store.root, again)
    assert _stored_mtimes(store) == before


@pytest.mark.shared_data
def test_a_changed_bad_log_is_retried_and_leaves_quarantine_once_it_loads(landing: Path, tmp_path: Path,
                                                                          shared_data: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    _land_all(store.root, scan_landing(store.root, str(landing)))
    bad = landing / "broken" / "scenario_bad.parquet"
    first = read_quarantine(store, str(landing / "broken"))
    assert first is not None
    stat = bad.stat()
    os.utime(bad, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))
    retry = scan_landing(store.root, str(landing))
    assert [Path(log.path).name for log in retry.new] == ["broken"]
    _land_all(store.root, retry)
    again = read_quarantine(store, str(landing / "broken"))
    assert again is not None and again.first_seen == first.first_seen and again.key != first.key
    bad.unlink()
    for part in (shared_data / AV2_FORECASTING).iterdir():
        shutil.copy(part, landing / "broken" / part.name)
    fixed = scan_landing(store.root, str(landing))
    _land_all(store.root, fixed)
    assert read_quarantine(store, str(landing / "broken")) is None
    assert list_quarantined(store) == []


@pytest.mark.shared_data
def test_a_removed_stored_log_is_ingested_again(landing: Path, tmp_path: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    _land_all(store.root, scan_landing(store.root, str(landing)))
    (seq_id, *_) = list_logs(store)
    store.delete(log_dir(seq_id))
    assert len(scan_landing(store.root, str(landing)).new) == 1


@pytest.mark.shared_data
def test_a_bad_log_replaced_by_a_copy_of_a_stored_one_leaves_quarantine_without_decoding(landing: Path,
                                                                                      tmp_path: Path,
                                                                                      shared_data: Path) -> None:
    store = ArtifactStore(str(tmp_path / "store"))
    _land_all(store.root, scan_landing(store.root, str(landing)))
    shutil.rmtree(landing / "broken")
    (landing / "broken").symlink_to(shared_data / AV2_FORECASTING, target_is_directory=True)
    plan = scan_landing(store.root, str(landing))
    assert plan.new == () and str(landing / "broken") in {log.path for log, _ in plan.already}
    assert list_quarantined(store) == []


def test_the_landing_key_follows_size_and_mtime_not_the_name_of_the_copy(tmp_path: Path) -> None:
    first = bad_scenario(tmp_path / "a")
    key = landing_key("av2-forecasting", first)
    assert landing_key("av2-forecasting", first) == key
    assert landing_key("av2", first) != key
    (first / "scenario_bad.parquet").write_bytes((first / "scenario_bad.parquet").read_bytes() + b"\0")
    assert landing_key("av2-forecasting", first) != key


def test_landing_locations_that_cannot_be_scanned_are_named(tmp_path: Path) -> None:
    assert landing_folder(tmp_path.as_uri()) == tmp_path
    with pytest.raises(FileNotFoundError, match="missing"):
        landing_folder(str(tmp_path / "missing"))
    with pytest.raises(ValueError, match="not a local folder"):
        landing_folder("mock://bucket/landing")  # object stores are mirrored instead (tests/tasks/test_s3_landing.py)
    with pytest.raises(FileNotFoundError, match="mock://bucket/landing: no such folder"):
        check_landing("mock://bucket/landing")
