"""ArtifactStore: paths, bytes/JSON, atomic files, staged directories, URI roots."""

from __future__ import annotations

from pathlib import Path

import pyarrow.fs as pafs
import pytest

from storage import ArtifactStore, CorruptArtifactError, UnsafePathError, normalize_relpath


@pytest.mark.parametrize("bad", ["../x", "a/../../x", "a/..", "/abs/path", "s3://b/k", "a\\b", "", "./"])
def test_paths_escaping_the_root_are_rejected(store: ArtifactStore, bad: str) -> None:
    with pytest.raises(UnsafePathError):
        store.write_bytes(bad, b"x")


def test_normalize_relpath() -> None:
    assert normalize_relpath("a//b/./c/") == "a/b/c"
    assert normalize_relpath("", allow_root=True) == ""


def test_bytes_json_list_delete(store: ArtifactStore) -> None:
    assert not store.exists("a/b.bin")
    store.write_bytes("a/b.bin", b"hello")
    store.write_json("a/c.json", {"z": 1, "a": [1.5, "x"]})
    assert store.read_bytes("a/b.bin") == b"hello"
    assert store.read_json("a/c.json") == {"z": 1, "a": [1.5, "x"]}
    assert store.listdir("a") == ["b.bin", "c.json"]
    assert store.listdir("missing") == []
    assert store.walk("") == ["a/b.bin", "a/c.json"]
    assert store.size("a/b.bin") == 5
    store.write_bytes("a/b.bin", b"replaced")
    assert store.read_bytes("a/b.bin") == b"replaced"
    assert store.delete("a/b.bin") and not store.exists("a/b.bin")
    assert not store.delete("a/b.bin")
    assert store.delete("a") and store.listdir("") == []


def test_missing_and_corrupt_files_name_the_artifact(store: ArtifactStore) -> None:
    with pytest.raises(FileNotFoundError, match="nothing.bin"):
        store.read_bytes("nothing.bin")
    store.write_bytes("bad.json", b"{not json")
    with pytest.raises(CorruptArtifactError, match="bad.json"):
        store.read_json("bad.json")


def test_failed_write_leaves_old_version_and_no_temporary(store: ArtifactStore) -> None:
    store.write_bytes("f.bin", b"old")
    with pytest.raises(RuntimeError):
        with store.open_output("f.bin") as out:
            out.write(b"partial")
            raise RuntimeError("crash mid-write")
    assert store.read_bytes("f.bin") == b"old"
    assert store.listdir("") == ["f.bin"]


def test_staged_directory_commits_and_replaces(store: ArtifactStore) -> None:
    with store.staged_directory("group") as tmp:
        assert tmp.startswith(".group.tmp-")
        store.write_bytes(f"{tmp}/a.txt", b"v1")
        store.write_bytes(f"{tmp}/sub/b.txt", b"v1")
        assert not store.exists("group")
    assert store.walk("group") == ["a.txt", "sub/b.txt"]
    with store.staged_directory("group") as tmp:
        store.write_bytes(f"{tmp}/a.txt", b"v2")
        assert store.read_bytes("group/a.txt") == b"v1"  # old version visible until commit
    assert store.walk("group") == ["a.txt"]
    assert store.read_bytes("group/a.txt") == b"v2"
    assert store.listdir("") == [".locks", "group"]  # no temporaries or old versions left (the commit lock stays)


def test_staged_directory_failure_keeps_previous_version(store: ArtifactStore, snapshot, tmp_path: Path) -> None:
    with store.staged_directory("logs/x") as tmp:
        store.write_bytes(f"{tmp}/a.txt", b"v1")
    before = snapshot(tmp_path)
    with pytest.raises(ValueError, match="boom"):
        with store.staged_directory("logs/x") as tmp:
            store.write_bytes(f"{tmp}/a.txt", b"v2")
            raise ValueError("boom")
    assert snapshot(tmp_path) == before
    assert store.listdir("logs") == ["x"]


def test_staged_directory_failure_on_fresh_path_leaves_nothing(store: ArtifactStore) -> None:
    with pytest.raises(KeyError):
        with store.staged_directory("logs/new") as tmp:
            store.write_bytes(f"{tmp}/a.txt", b"v1")
            raise KeyError("x")
    assert store.listdir("logs") == []


def test_interrupted_swap_is_recovered(store: ArtifactStore) -> None:
    """A crash between 'old aside' and 'new in' leaves only .x.old-*; the next staging restores it."""
    with store.staged_directory("g/x") as tmp:
        store.write_bytes(f"{tmp}/a.txt", b"v1")
    store.filesystem.move(store._path("g/x"), store._path("g/.x.old-deadbeef"))  # simulate the crash
    assert not store.exists("g/x")
    with pytest.raises(RuntimeError):
        with store.staged_directory("g/x"):
            assert store.read_bytes("g/x/a.txt") == b"v1"  # restored before staging starts
            raise RuntimeError
    assert store.read_bytes("g/x/a.txt") == b"v1"
    assert store.listdir("g") == ["x"]


def test_file_uri_root(tmp_path: Path) -> None:
    uri_store = ArtifactStore(f"file://{tmp_path}/r")
    assert uri_store.renames_atomically
    uri_store.write_bytes("a/b.bin", b"1")
    assert (tmp_path / "r" / "a" / "b.bin").read_bytes() == b"1"
    assert uri_store.uri("a/b.bin") == f"file://{tmp_path}/r/a/b.bin"
    assert ArtifactStore(tmp_path / "r").read_bytes("a/b.bin") == b"1"


def test_subtree_filesystem_root(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    fs = pafs.SubTreeFileSystem(str(tmp_path / "sub"), pafs.LocalFileSystem())
    sub = ArtifactStore("", filesystem=fs)
    assert sub.renames_atomically
    with sub.staged_directory("g") as tmp:
        sub.write_bytes(f"{tmp}/a.bin", b"x")
    assert (tmp_path / "sub" / "g" / "a.bin").read_bytes() == b"x"
    with sub.local_path_for_read("g/a.bin") as path:
        assert Path(path).read_bytes() == b"x"


def test_object_store_staged_directory_is_marker_last(mock_store: ArtifactStore) -> None:
    with mock_store.staged_directory("g") as tmp:
        mock_store.write_bytes(f"{tmp}/data.bin", b"v1")
        mock_store.write_bytes(f"{tmp}/stale.bin", b"v1")
        mock_store.write_bytes(f"{tmp}/_SUCCESS.json", b"{}")
    assert mock_store.walk("g") == ["_SUCCESS.json", "data.bin", "stale.bin"]
    with pytest.raises(RuntimeError):
        with mock_store.staged_directory("g") as tmp:
            mock_store.write_bytes(f"{tmp}/data.bin", b"v2")
            raise RuntimeError
    assert mock_store.read_bytes("g/data.bin") == b"v1"
    assert mock_store.listdir("") == ["g"]
    with mock_store.staged_directory("g") as tmp:
        mock_store.write_bytes(f"{tmp}/data.bin", b"v2")
        mock_store.write_bytes(f"{tmp}/_SUCCESS.json", b"{}")
    assert mock_store.walk("g") == ["_SUCCESS.json", "data.bin"]  # files of the old version removed
    assert mock_store.read_bytes("g/data.bin") == b"v2"
    assert mock_store.listdir("") == ["g"]
    assert mock_store.uri("g/data.bin") == "mock:bucket/prefix/g/data.bin"


def test_store_pickles_for_workers(tmp_path: Path) -> None:
    import pickle

    for root in (str(tmp_path / "p"), f"file://{tmp_path}/p"):
        original = ArtifactStore(root)
        original.write_bytes("x.bin", b"1")
        clone = pickle.loads(pickle.dumps(original))
        assert clone.uri("x.bin") == original.uri("x.bin") and clone.read_bytes("x.bin") == b"1"
