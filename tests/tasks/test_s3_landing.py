"""A landing location in a bucket of an S3-compatible server (moto on 127.0.0.1, credentials from the environment,
the endpoint as a URI option): scanned through a local mirror, its logs ingested once by landing key (the same keys
from a fresh mirror), named by their URIs, a bad one quarantined."""

from __future__ import annotations

from pathlib import Path

import pytest

from storage import ArtifactStore, list_logs, read_scene_log
from storage.landing import list_quarantined, read_ingested
from tasks.landing import ingest_landing_log, scan_landing
from tests.s3_server import S3Server
from tests.tasks.landing_files import WAYMO_SCENARIO, bad_scenario


def _upload(bucket_uri: str, relpath: str, local: Path) -> None:
    ArtifactStore(bucket_uri).write_bytes(relpath, local.read_bytes())


def landing_bucket(s3: S3Server, shared_data: Path, tmp_path: Path) -> str:
    """A landing prefix holding the Waymo motion scenario sample and a broken AV2 forecasting look-alike."""
    landing = s3.fresh_uri("landing", "nightly")
    _upload(landing, "waymo/motion.tfrecord", shared_data / WAYMO_SCENARIO)
    broken = bad_scenario(tmp_path / "broken")
    _upload(landing, "broken/scenario_bad.parquet", broken / "scenario_bad.parquet")
    return landing


@pytest.mark.shared_data
def test_a_landing_bucket_is_ingested_once(s3_server: S3Server, shared_data: Path, tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SIMSPLAT_LANDING_MIRROR", str(tmp_path / "mirrors"))
    store_uri, landing = s3_server.fresh_uri("store", "landed"), landing_bucket(s3_server, shared_data, tmp_path)
    plan = scan_landing(store_uri, landing)
    base = landing.split("?")[0] + "/"
    assert sorted(log.path.split("?")[0].removeprefix(base) for log in plan.new) == ["broken", "waymo/motion.tfrecord"]
    assert all(log.path.endswith(s3_server.options) for log in plan.new)  # named by URI, not by the mirror
    outcomes = {log.source: ingest_landing_log(store_uri, log) for log in plan.new}
    stored = outcomes["waymo-scenario"].stored
    assert stored is not None and outcomes["av2-forecasting"].error
    store = ArtifactStore(store_uri)
    assert list_logs(store) == [stored.summary.seq_id]
    assert read_scene_log(store, stored.summary.seq_id).tracks  # readable from the bucket
    (waymo,) = [log for log in plan.new if log.source == "waymo-scenario"]
    record = read_ingested(store, waymo.key)
    assert record is not None and record.path == waymo.path and record.seq_id == stored.summary.seq_id
    (quarantined,) = list_quarantined(store)
    assert quarantined.path.split("?")[0].endswith("/broken") and "position_x" in quarantined.error
    assert f"{base}broken/scenario_bad.parquet: column 'position_x'" in quarantined.error  # the file in the bucket

    monkeypatch.setenv("SIMSPLAT_LANDING_MIRROR", str(tmp_path / "fresh-mirrors"))  # another machine: same keys
    again = scan_landing(store_uri, landing)
    assert (again.new, [s for _, s in again.already], len(again.quarantined_known)) == \
        ((), [stored.summary.seq_id], 1)
