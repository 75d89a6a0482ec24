"""``ArtifactStore`` in a bucket of an S3-compatible server (moto on 127.0.0.1): every kind of file round-trips,
URIs keep their options and never carry credentials, writes are all-or-nothing (one PUT per file, groups marker-last),
and a landing folder in a bucket is mirrored locally with only changed objects downloaded."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.fs as pafs
import pytest

from simsplat_core.world.config import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import METRICS_SCHEMA, ArtifactStore, list_logs, read_exr, read_scene_log, write_exr, write_scene_log
from storage.pictures import write_png
from storage.remote_folder import fetched, is_remote, list_remote_files, mirror_folder
from storage.uris import CredentialsInUriError, join_uri, split_name
from tests.s3_server import S3Server


def _objects(s3: S3Server, uri: str) -> list[str]:
    """Every object under the location ``uri`` as the server lists it (paths below it)."""
    return sorted(s3.objects(uri))


@pytest.fixture()
def bucket(s3_server: S3Server) -> ArtifactStore:
    return ArtifactStore(s3_server.fresh_uri("store", "unit"))


def test_uris_keep_their_options_after_the_path(s3_server: S3Server, bucket: ArtifactStore) -> None:
    uri = bucket.uri("logs/seq0/frames.parquet")
    assert uri.startswith(bucket.uri().split("?")[0] + "/logs/seq0/frames.parquet?") and uri.endswith(s3_server.options)
    bucket.write_bytes("sub/x.bin", b"abc")
    assert ArtifactStore(bucket.uri("sub")).read_bytes("x.bin") == b"abc"  # a sub-store opens from the URI
    assert join_uri("s3://b/p?o=1", "a/b") == "s3://b/p/a/b?o=1" and split_name("s3://b/p/x.png?o=1") == (
        "s3://b/p?o=1", "x.png")
    assert not bucket.renames_atomically and is_remote(bucket.uri()) and not is_remote("file:///tmp/x")


@pytest.mark.parametrize("credentials", ["?access_key=AKIA&secret_key=hush&", "?session_token=hush&", "?"])
def test_credentials_in_a_uri_are_refused_without_showing_them(s3_server: S3Server, credentials: str) -> None:
    userinfo = "AKIA:hush@" if credentials == "?" else ""
    with pytest.raises(CredentialsInUriError, match="AWS_ACCESS_KEY_ID") as caught:
        ArtifactStore(f"s3://{userinfo}store/p{credentials}{s3_server.options}")
    assert "hush" not in str(caught.value) and "store/p" in str(caught.value)


def test_every_kind_of_file_round_trips(bucket: ArtifactStore) -> None:
    log = generate_log(0, WorldConfig(num_frames=4, width=32, height=24))
    written = write_scene_log(bucket, log)
    back = read_scene_log(bucket, log.seq_id)
    assert list_logs(bucket) == [log.seq_id] and back.num_frames == log.num_frames
    assert len(back.images) == len(log.images) and back.images[0].image is not None  # EXRs through OpenImageIO
    np.testing.assert_allclose(back.images[0].image, log.images[0].image, atol=1e-3)
    assert write_scene_log(bucket, log).skipped and written.relpath == f"logs/{log.seq_id}"

    depth = np.linspace(0.0, 9.0, 24 * 32, dtype=np.float32).reshape(24, 32)
    write_exr(bucket, "renders/0.exr", {"R": depth, "G": depth, "B": depth, "Z": depth})  # OpenImageIO via a local file
    np.testing.assert_array_equal(read_exr(bucket, "renders/0.exr")["Z"], depth)

    metrics = pa.table({"run_id": ["r"], "seq_id": ["s"], "stage": ["x"], "name": ["m"], "value": [1.5], "unit": [""]})
    bucket.write_table("runs/r/tables/metrics.parquet", metrics, METRICS_SCHEMA)
    assert bucket.read_table("runs/r/tables/metrics.parquet", METRICS_SCHEMA).column("value").to_pylist() == [1.5]

    uri = write_png(bucket.uri("pictures/view.png"), np.full((4, 6, 3), 200, np.uint8))
    assert uri == bucket.uri("pictures/view.png") and bucket.read_bytes("pictures/view.png")[:4] == b"\x89PNG"
    bucket.write_json("runs/r/run.json", {"status": "completed"})
    assert bucket.read_json("runs/r/run.json") == {"status": "completed"}
    assert {"renders/0.exr", "pictures/view.png", "runs/r/run.json"} <= set(bucket.walk())
    assert not [f for f in bucket.walk() if ".tmp-" in f]  # no staging leftovers


def test_no_object_appears_before_its_single_put(s3_server: S3Server, bucket: ArtifactStore) -> None:
    bucket.write_bytes("a.bin", b"old")
    with bucket.open_output("a.bin") as out:
        out.write(b"new, but not yet sent")
        assert bucket.read_bytes("a.bin") == b"old"  # buffered: nothing reached the server
    assert bucket.read_bytes("a.bin") == b"new, but not yet sent"

    with pytest.raises(RuntimeError), bucket.open_output("b.bin") as out:
        out.write(b"half")
        raise RuntimeError("writer died")
    with pytest.raises(RuntimeError), bucket.open_output("a.bin") as out:
        out.write(b"half")
        raise RuntimeError("writer died")
    assert _objects(s3_server, bucket.uri()) == ["a.bin"] and bucket.read_bytes("a.bin") == b"new, but not yet sent"


def test_a_group_that_fails_midway_leaves_the_previous_version(s3_server: S3Server, bucket: ArtifactStore) -> None:
    with bucket.staged_directory("group") as tmp:
        bucket.write_bytes(f"{tmp}/data.bin", b"v1")
        bucket.write_json(f"{tmp}/_SUCCESS.json", {"version": 1})
    with pytest.raises(RuntimeError), bucket.staged_directory("group") as tmp:
        bucket.write_bytes(f"{tmp}/data.bin", b"v2")
        assert _objects(s3_server, bucket.uri("group")) == ["_SUCCESS.json", "data.bin"]  # staged aside, hidden
        raise RuntimeError("writer died mid-group")
    assert bucket.read_bytes("group/data.bin") == b"v1" and bucket.read_json("group/_SUCCESS.json") == {"version": 1}
    assert _objects(s3_server, bucket.uri()) == ["group/_SUCCESS.json", "group/data.bin"]


def test_a_crash_during_the_group_copy_leaves_no_marker(bucket: ArtifactStore) -> None:
    with bucket.staged_directory("group") as tmp:
        bucket.write_bytes(f"{tmp}/data.bin", b"v1")
        bucket.write_json(f"{tmp}/_SUCCESS.json", {"version": 1})
    bucket._fs = _CopyDiesAfter(bucket.filesystem, copies=1)  # the connection drops during the copy into place
    with pytest.raises(OSError, match="connection lost"), bucket.staged_directory("group") as tmp:
        bucket.write_bytes(f"{tmp}/data.bin", b"v2")
        bucket.write_bytes(f"{tmp}/more.bin", b"v2")
        bucket.write_json(f"{tmp}/_SUCCESS.json", {"version": 2})
    assert not bucket.exists("group/_SUCCESS.json")  # incomplete: readers that need the marker see no group
    assert not any(f.startswith(".") for f in bucket.listdir(""))  # the staged copy was removed


def test_threads_of_one_process_take_turns_on_a_shared_object(bucket: ArtifactStore) -> None:
    bucket.write_json("counter.json", 0)

    def add_one() -> None:
        with bucket.exclusive("counter.json"):
            value = bucket.read_json("counter.json")
            bucket.write_json("counter.json", value + 1)

    with ThreadPoolExecutor(4) as pool:
        for _ in range(12):
            pool.submit(add_one)
    assert bucket.read_json("counter.json") == 12  # no read-modify-write lost between the threads


class _CopyDiesAfter:
    """A filesystem that forwards everything to ``inner`` but fails every ``copy_file`` after the first ``copies``."""

    def __init__(self, inner: pafs.FileSystem, copies: int) -> None:
        self._inner, self._left = inner, copies

    def copy_file(self, src: str, dest: str) -> None:
        if self._left <= 0:
            raise OSError("connection lost")
        self._left -= 1
        self._inner.copy_file(src, dest)

    def __getattr__(self, name: str) -> object:
        return getattr(self._inner, name)


def test_a_landing_folder_in_a_bucket_is_mirrored_and_fetched(s3_server: S3Server, tmp_path: Path) -> None:
    landing = ArtifactStore(s3_server.fresh_uri("landing", "mirror"))
    landing.write_bytes("a.tfrecord", b"A" * 10)
    landing.write_bytes("folder/x.parquet", b"X")
    landing.write_bytes(".hidden/skip.bin", b"-")
    assert [f.relpath for f in list_remote_files(landing.uri())] == ["a.tfrecord", "folder/x.parquet"]

    mirror = mirror_folder(landing.uri(), tmp_path / "mirror")
    stamps = {p: (mirror / p).stat().st_mtime_ns for p in ("a.tfrecord", "folder/x.parquet")}
    assert {f.relpath: f.mtime_ns for f in list_remote_files(landing.uri())} == stamps  # the objects' times
    (mirror / "a.tfrecord").write_bytes(b"B" * 10)  # same size: only the time tells it is not the object
    os.utime(mirror / "a.tfrecord", ns=(stamps["a.tfrecord"], stamps["a.tfrecord"]))
    landing.delete("folder")
    mirror_folder(landing.uri(), mirror)
    assert (mirror / "a.tfrecord").read_bytes() == b"B" * 10  # unchanged size and time: not downloaded again
    assert not (mirror / "folder").exists()

    with fetched(landing.uri("a.tfrecord")) as local:
        assert local.name == "a.tfrecord" and local.read_bytes() == b"A" * 10
    assert not local.exists()
    with pytest.raises(FileNotFoundError, match="no such folder"):
        mirror_folder(s3_server.fresh_uri("landing", "absent"), tmp_path / "none")
