"""``simsplat run`` with its store, landing location and export in buckets of an S3-compatible server (moto on
127.0.0.1, credentials from the environment, the endpoint as a URI option): ingest, a short reconstruction, align,
mine (K=1) and export; killed with SIGKILL after its first stored artifact and run again, the second run reuses
what the first finished, completes the rest, and every artifact reads back."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from storage import ArtifactStore, list_logs, list_scenes, read_scene, read_scene_log
from storage.datasets import DatasetFolder, list_datasets
from storage.edits import read_edit_records
from storage.run_records import list_run_ids, read_run_record
from storage.uris import split_name
from tests.s3_server import S3Server
from tests.tasks.test_s3_landing import landing_bucket

REPO = Path(__file__).resolve().parents[2]
SIMSPLAT = Path(sys.executable).parent / "simsplat"
RUN_OPTIONS = ("--sequences", "1", "--frames", "8", "--width", "64", "--height", "48", "--iterations", "20",
               "--runner", "threads", "--workers", "1", "--mine", "1")


def _start_run(store: str, landing: str, export: str, api_url: str, log: Path) -> subprocess.Popen:
    """``simsplat run`` over the buckets in a subprocess (the session's Prefect API), its output appended to ``log``."""
    env = {**os.environ, "PREFECT_API_URL": api_url, "PYTHONPATH": str(REPO), "SIMSPLAT_PROGRESS": "0"}
    command = [str(SIMSPLAT), "run", "--store", store, "--landing", landing, "--export", export, *RUN_OPTIONS]
    with open(log, "ab") as out:
        return subprocess.Popen(command, env=env, stdout=out, stderr=subprocess.STDOUT, cwd=REPO)


def _markers(s3: S3Server, store: str) -> dict[str, int]:
    """Modification time of every committed ``_SUCCESS.json`` marker (a finished artifact) in the store, by path;
    markers inside a hidden staging prefix (``.<name>.tmp-<uuid>/``, a group not copied into place yet) are not."""
    return {path: mtime for path, mtime in s3.objects(store).items()
            if path.endswith("_SUCCESS.json") and not any(part.startswith(".") for part in path.split("/"))}


def _kill_after_first_marker(s3: S3Server, store: str, process: subprocess.Popen, log: Path) -> None:
    try:
        while not _markers(s3, store):
            assert process.poll() is None, log.read_text()[-4000:]
            time.sleep(0.5)
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()


def _dataset_manifest(entry: dict) -> dict:
    parent, name = split_name(str(entry["uri"]))
    assert name == entry["name"]
    manifest = DatasetFolder(parent, name).read_manifest()
    assert manifest is not None, entry
    return manifest


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_a_killed_run_over_buckets_resumes(prefect_api_url: str, s3_server: S3Server, shared_data: Path,
                                           tmp_path: Path) -> None:
    store_uri, export = s3_server.fresh_uri("store", "nightly"), s3_server.fresh_uri("export", "datasets")
    landing = landing_bucket(s3_server, shared_data, tmp_path)
    log = tmp_path / "run.log"
    _kill_after_first_marker(s3_server, store_uri, _start_run(store_uri, landing, export, prefect_api_url, log), log)
    finished = _markers(s3_server, store_uri)

    assert _start_run(store_uri, landing, export, prefect_api_url, log).wait(timeout=1200) == 0, log.read_text()[-4000:]
    after = _markers(s3_server, store_uri)
    assert {p: after.get(p) for p in finished} == finished  # what the killed run finished was reused, not redone
    store = ArtifactStore(store_uri)
    records = [read_run_record(store, r) for r in list_run_ids(store)]
    (run,) = [r for r in records if r is not None and r.status == "completed"]
    assert run.counts["quarantined"] == 1

    seq_ids = list_logs(store)
    assert len(seq_ids) == 2  # the synthetic log and the Waymo motion scenario from the landing bucket
    for seq_id in seq_ids:
        assert read_scene_log(store, seq_id).num_frames > 0
    (synthetic,) = [s for s in seq_ids if list_scenes(store, s)]
    assert read_scene(store, synthetic).records is not None
    assert any(row.export for row in read_edit_records(store, run.run_id))  # mined: an accepted scenario
    (dataset,) = list_datasets(store)
    assert _dataset_manifest(dataset)["scenarios"]  # exported into the export bucket
    assert str(dataset["uri"]).startswith(export.split("?")[0])
    assert not [p for p in s3_server.objects(export) if ".tmp-" in p]
