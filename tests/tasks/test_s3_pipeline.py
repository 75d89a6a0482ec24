"""The pipeline with its store, landing location and export in buckets of an S3-compatible server (moto on
127.0.0.1, credentials from the environment, the endpoint as a URI option):

* a landing bucket scanned, its logs ingested once by content key, a bad one quarantined (the task functions);
* ``simsplat run`` over buckets (ingest, a short reconstruction, align, mine K=1, export), killed with SIGKILL
  after its first stored artifact and run again: what the first run finished is reused, the rest completes,
  and every artifact reads back.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.fs as pafs
import pytest

from storage import ArtifactStore, list_logs, list_scenes, read_scene, read_scene_log
from storage.datasets import DatasetFolder, list_datasets
from storage.edits import read_edit_records
from storage.landing import list_quarantined, read_ingested
from storage.run_records import list_run_ids, read_run_record
from tasks.landing import ingest_landing_log, scan_landing
from tests.s3_server import S3Server
from tests.tasks.landing_files import WAYMO_SCENARIO

REPO = Path(__file__).resolve().parents[2]


def _upload(bucket_uri: str, relpath: str, local: Path) -> None:
    ArtifactStore(bucket_uri).write_bytes(relpath, local.read_bytes())


def _landing_bucket(s3: S3Server, shared_data: Path, tmp_path: Path) -> str:
    """A landing prefix holding the Waymo motion scenario sample and a broken AV2 forecasting look-alike."""
    from tests.tasks.landing_files import bad_scenario

    landing = s3.fresh_uri("landing", "nightly")
    _upload(landing, "waymo/motion.tfrecord", shared_data / WAYMO_SCENARIO)
    broken = bad_scenario(tmp_path / "broken")
    _upload(landing, "broken/scenario_bad.parquet", broken / "scenario_bad.parquet")
    return landing


@pytest.mark.shared_data
def test_a_landing_bucket_is_ingested_once(s3_server: S3Server, shared_data: Path, tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SIMSPLAT_LANDING_MIRROR", str(tmp_path / "mirrors"))
    store_uri, landing = s3_server.fresh_uri("store", "landed"), _landing_bucket(s3_server, shared_data, tmp_path)
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

    monkeypatch.setenv("SIMSPLAT_LANDING_MIRROR", str(tmp_path / "fresh-mirrors"))  # another machine: same keys
    again = scan_landing(store_uri, landing)
    assert (again.new, [s for _, s in again.already], len(again.quarantined_known)) == \
        ((), [stored.summary.seq_id], 1)


# ------------------------------------------------------------------------------------------- a killed run
RUN_OPTIONS = ("--sequences", "1", "--frames", "8", "--width", "64", "--height", "48", "--iterations", "20",
               "--runner", "threads", "--workers", "1", "--mine", "1")


def _simsplat_run(store: str, landing: str, export: str, api_url: str, log: Path) -> subprocess.Popen:
    env = {**os.environ, "PREFECT_API_URL": api_url, "PYTHONPATH": str(REPO), "SIMSPLAT_PROGRESS": "0"}
    with open(log, "ab") as out:
        return subprocess.Popen([str(Path(sys.executable).parent / "simsplat"), "run", "--store", store, "--landing", landing,
                                 "--export", export, *RUN_OPTIONS], env=env, stdout=out, stderr=subprocess.STDOUT,
                                cwd=REPO)


def _markers(store: ArtifactStore) -> dict[str, int]:
    """Modification time of every ``_SUCCESS.json`` marker in the store (finished artifacts), by path."""
    return {path: store.filesystem.get_file_info(store.uri(path).split("://", 1)[1].split("?")[0]).mtime_ns
            for path in store.walk() if path.endswith("_SUCCESS.json")}


def _wait_for_a_marker(store: ArtifactStore, process: subprocess.Popen, log: Path) -> None:
    while not _markers(store):
        assert process.poll() is None, log.read_text()[-4000:]
        time.sleep(0.5)


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_a_killed_run_over_buckets_resumes(prefect_api_url: str, s3_server: S3Server, shared_data: Path,
                                           tmp_path: Path) -> None:
    store_uri, export = s3_server.fresh_uri("store", "nightly"), s3_server.fresh_uri("export", "datasets")
    landing = _landing_bucket(s3_server, shared_data, tmp_path)
    store, log = ArtifactStore(store_uri), tmp_path / "run.log"
    first = _simsplat_run(store_uri, landing, export, prefect_api_url, log)
    try:
        _wait_for_a_marker(store, first, log)
    finally:
        first.send_signal(signal.SIGKILL)
        first.wait()
    finished = _markers(store)
    assert not [p for p in store.walk() if "/." in f"/{p}" and "_SUCCESS.json" in p]  # no staged marker visible

    second = _simsplat_run(store_uri, landing, export, prefect_api_url, log)
    assert second.wait(timeout=900) == 0, log.read_text()[-4000:]
    after = _markers(store)
    assert {p: after.get(p) for p in finished} == finished  # what the killed run finished was reused, not redone
    (run_id,) = [r for r in list_run_ids(store) if (read_run_record(store, r) or None) and
                 read_run_record(store, r).status == "completed"]
    assert read_run_record(store, run_id).counts["quarantined"] == 1

    seq_ids = list_logs(store)
    assert len(seq_ids) == 2  # the synthetic log and the Waymo motion scenario
    for seq_id in seq_ids:
        read_scene_log(store, seq_id, load_images=True)
    (synthetic,) = [s for s in seq_ids if list_scenes(store, s)]
    assert read_scene(store, synthetic, list_scenes(store, synthetic)[0]).records
    rows = read_edit_records(store, run_id)
    assert rows and any(r.export for r in rows)
    (dataset,) = list_datasets(store)
    manifest = _read_dataset(str(dataset["uri"]), str(dataset["name"]))
    assert manifest["scenarios"]  # the accepted scenario went out into the export bucket
    assert not [i.path for i in s3_server.filesystem().get_file_info(pafs.FileSelector("export", recursive=True))
                if ".tmp-" in i.path]


def _read_dataset(uri: str, name: str) -> dict:
    from storage.uris import split_name

    parent, last = split_name(uri)
    assert last == name
    manifest = DatasetFolder(parent, name).read_manifest()
    assert manifest is not None, uri
    return manifest
