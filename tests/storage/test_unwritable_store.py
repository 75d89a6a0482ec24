"""A full disk or an unwritable store: a clear error naming the store and the reason, no partial artifact, no
temporary left in listings, and the previous version of the artifact intact.

The full disk is injected under the store's own writes: the store's filesystem is wrapped so that every output
stream fails with ``ENOSPC`` once the bytes written since the disk "filled up" pass a budget (the temporary file is
really created and partly written first). This needs no root and no mount. The unwritable store is a root that is a
file, which refuses writes for root and ordinary users alike."""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import Any

import pyarrow.fs as pafs
import pytest

from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, read_log_manifest, read_scene_log, write_scene_log
from storage.errors import StoreNotWritableError

WORLD = WorldConfig(num_frames=4, width=32, height=24)


class _FillingStream:
    """An output stream that raises ``ENOSPC`` once its disk's byte budget is spent (what it wrote so far stays)."""

    def __init__(self, inner: Any, disk: _FullDisk) -> None:
        self._inner, self._disk = inner, disk

    def write(self, data: Any) -> int:
        size = len(memoryview(data).cast("B"))
        if size > self._disk.budget:
            self._inner.write(memoryview(data).cast("B")[: self._disk.budget])
            self._disk.budget = 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._disk.budget -= size
        return int(self._inner.write(data))

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def __enter__(self) -> _FillingStream:
        return self

    def __exit__(self, *exc: object) -> None:
        self._inner.close()


class _FullDisk:
    """The local filesystem with ``budget`` bytes left for new output streams."""

    def __init__(self, inner: pafs.FileSystem, budget: int) -> None:
        self._inner, self.budget = inner, budget

    def open_output_stream(self, path: str, *args: Any, **kwargs: Any) -> _FillingStream:
        return _FillingStream(self._inner.open_output_stream(path, *args, **kwargs), self)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


def _fill_disk(store: ArtifactStore, monkeypatch: pytest.MonkeyPatch, budget: int) -> None:
    monkeypatch.setattr(store, "_fs", _FullDisk(store.filesystem, budget))


def _every_name(root: Path) -> list[str]:
    """Every file and directory below ``root``, hidden ones included, relative to it."""
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def test_a_full_disk_during_a_file_write_names_the_store_and_keeps_the_previous_version(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    store = ArtifactStore(tmp_path / "store")
    store.write_bytes("runs/r1/notes.txt", b"previous version")
    before = _every_name(tmp_path / "store")
    _fill_disk(store, monkeypatch, budget=100)
    with pytest.raises(StoreNotWritableError, match="the disk is full") as raised:
        store.write_bytes("runs/r1/notes.txt", b"x" * 10_000)
    message = str(raised.value)
    assert store.root in message and "runs/r1/notes.txt" in message
    assert isinstance(raised.value, OSError) and raised.value.__cause__.errno == errno.ENOSPC  # type: ignore[union-attr]
    assert _every_name(tmp_path / "store") == before  # the partly written temporary is gone
    assert store.read_bytes("runs/r1/notes.txt") == b"previous version"


def test_a_full_disk_during_a_staged_group_write_leaves_the_previous_log(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    store = ArtifactStore(tmp_path / "store")
    first = generate_log(seed=1, config=WORLD, seq_id="s")
    written = write_scene_log(store, first)
    before = _every_name(tmp_path / "store")
    _fill_disk(store, monkeypatch, budget=3_000)  # room for a table or two of the new version, not all of it
    with pytest.raises(StoreNotWritableError, match=r"the disk is full") as raised:
        write_scene_log(store, generate_log(seed=2, config=WORLD, seq_id="s"))
    assert store.root in str(raised.value) and ".parquet" in str(raised.value)
    assert _every_name(tmp_path / "store") == before  # no staged directory, no temporary, nothing half-written
    assert store.listdir("logs") == ["s"]
    monkeypatch.undo()
    assert read_log_manifest(store, "s")["key"] == written.key
    assert read_scene_log(store, "s").num_frames == first.num_frames


def test_a_store_whose_root_is_a_file_is_refused_before_any_work(tmp_path: Path) -> None:
    root = tmp_path / "not-a-directory"
    root.write_text("a file where the store should be")
    for store in (ArtifactStore(root), ArtifactStore(root / "below")):
        with pytest.raises(StoreNotWritableError, match="a path on the way is a file, not a directory") as raised:
            store.check_writable()
        assert store.root in str(raised.value)
    assert root.read_text() == "a file where the store should be"


def test_a_writable_store_passes_the_probe_and_keeps_no_trace(tmp_path: Path) -> None:
    store = ArtifactStore(tmp_path / "new" / "store")
    store.check_writable()  # creates the root
    assert (tmp_path / "new" / "store").is_dir() and _every_name(tmp_path / "new" / "store") == []


def test_a_read_only_filesystem_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    store = ArtifactStore(tmp_path / "store")

    def read_only(path: str, *args: Any, **kwargs: Any) -> Any:
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), path)

    _fill_disk(store, monkeypatch, budget=0)
    monkeypatch.setattr(store.filesystem, "open_output_stream", read_only)
    with pytest.raises(StoreNotWritableError, match="the filesystem is read-only"):
        store.check_writable()
