"""``ArtifactStore``: one artifact root (local path or object-store URI) over ``pyarrow.fs``.

Artifacts are addressed by *relative paths* with ``/`` separators (``"logs/seq0/frames.parquet"``).
A path that is absolute, contains ``..`` or a URI scheme is rejected with ``UnsafePathError``, so no
artifact can escape the root.

Atomicity (``DESIGN.md``: every write is atomic):

* **Files.** On a local filesystem a file is written to ``<name>.tmp-<uuid>`` in the same directory
  and renamed over the destination (``rename(2)`` is atomic and replaces an older version). On object
  stores (S3, GCS, ...) a rename is a copy, so the bytes are buffered in memory and sent as one PUT,
  which the store makes visible all-or-nothing; nothing is uploaded when the writer fails.
* **Groups of files** (``staged_directory``). Locally, the group is written under a hidden temporary
  sibling ``.<name>.tmp-<uuid>/`` and renamed into place; an older version is first renamed aside to
  ``.<name>.old-<uuid>/`` and deleted only after the new one is in place, so a crash never leaves a
  half-written group and never loses the previous one (an interrupted swap is undone by the next
  ``staged_directory`` on the same path). On object stores no prefix rename exists: the staged objects
  are copied into place *marker-last* — every file whose name starts with ``_`` (``_SUCCESS.json``)
  is removed from the old version first and copied last — so readers that require the marker never
  see a mixed group; a crash during that copy leaves the group without its marker (incomplete), and
  the previous version is not kept.
* **Concurrent writers** (two runs on one store). Locally the commit of a group (undoing an interrupted swap, the
  two renames) holds an exclusive ``flock`` on a lock file named after the group under ``.locks/``, so two runs
  committing the same content-keyed group one after the other each leave a complete version (the later one wins)
  and never undo each other's swap. Object stores have no lock: there, one run per store at a time.

**Object stores in detail** (an object store has no rename, so nothing is ever "moved into place"):

* A file is one PUT of its whole content, made only after the writer finished without error; the object does not
  exist (or keeps its previous content) until that request completes, and a writer killed before it leaves
  nothing. Readers never see part of a file. (A large file goes as a multipart upload, which the store likewise
  shows only once it is completed; one abandoned by a killed writer stays invisible until a bucket lifecycle rule
  aborts it.) Libraries that need a local file (OpenImageIO for EXR, OpenCV for
  MP4) write to a local temporary file that is then sent as that one PUT (``local_path_for_write``).
* A group is staged under a hidden ``.<name>.tmp-<uuid>/`` prefix, then copied into place marker-last (server-side
  copies), and the staged prefix is deleted. The marker (``_SUCCESS.json``, which carries the content key readers
  and re-runs check) is the last object written, so a group is complete exactly when its marker is there. A
  crash during the copy leaves the group without a marker: it reads as absent, the next run rewrites it, and the
  previous version of that group is gone (its marker was removed first). The hidden staged prefix of a killed
  writer may stay behind; it is never read.
* ``exclusive`` is not a lock there (see its docstring). Two runs on one bucket stay safe because everything they
  write is either a content-keyed artifact (both would write identical bytes, each file one PUT, so whichever
  PUT lands last leaves the same content) or a record of their own run (``runs/<run_id>``, ``edits/<run_id>``).
  The exception is a read-modify-write of one shared object, the edits table of a run appended by several
  *processes* at once (Ray workers of one run mining different sequences): the last PUT wins and the rows the
  other appended in that moment are missing from the table, while their edit folders stay complete. Threads of
  one process take turns (a process lock), and locally ``flock`` serialises every process.

A write that fails because the store cannot be written (disk full, read-only filesystem, permission denied, a file
where a directory should be) raises ``StoreNotWritableError`` naming the file, the store and the reason, after the
same cleanup: no partial artifact and the previous version intact. ``check_writable`` probes a store before a run
does any work.

Temporary names start with ``.`` so listings of artifact groups can ignore them. A writer killed
with SIGKILL can leave a hidden ``.tmp-`` directory behind; it is never read and can be deleted.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import logging
import os
import tempfile
import threading
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pyarrow as pa
import pyarrow.fs as pafs

from storage import parquet_io
from storage.errors import CorruptArtifactError, StoreNotWritableError, UnsafePathError
from storage.uris import is_uri, join_uri, reject_credentials, split_query

logger = logging.getLogger(__name__)

TMP_TAG = ".tmp-"
OLD_TAG = ".old-"
#: Files whose base name starts with this prefix are commit markers (written last on object stores).
MARKER_PREFIX = "_"
#: Hidden folder of the lock files that serialise commits of one group (local stores).
LOCKS_DIR = ".locks"
#: Write failures that mean the store cannot be written, by ``errno``, and how a message says it.
UNWRITABLE_REASONS: dict[int, str] = {
    errno.ENOSPC: "the disk is full",
    errno.EDQUOT: "the disk quota is exceeded",
    errno.EROFS: "the filesystem is read-only",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.ENOTDIR: "a path on the way is a file, not a directory",
    errno.EEXIST: "a path on the way is a file, not a directory",
}


def normalize_relpath(relpath: str, *, allow_root: bool = False) -> str:
    """Canonical form of a relative artifact path (``"a//b/./c"`` -> ``"a/b/c"``).

    Raises:
        UnsafePathError: absolute path, ``..`` component, backslash, URI scheme, or empty path
            (unless ``allow_root``).
    """
    if not isinstance(relpath, str):
        raise TypeError(f"artifact path must be a str, got {type(relpath).__name__}")
    if relpath.startswith("/") or "://" in relpath or "\\" in relpath:
        raise UnsafePathError(f"artifact path {relpath!r} must be relative to the store root, with '/' separators")
    parts = [p for p in relpath.split("/") if p not in ("", ".")]
    if ".." in parts:
        raise UnsafePathError(f"artifact path {relpath!r} escapes the store root ('..' is not allowed)")
    if not parts and not allow_root:
        raise UnsafePathError("artifact path is empty (the store root itself is not an artifact)")
    return "/".join(parts)


def join_relpath(*parts: str) -> str:
    """Join relative path pieces with ``/``, skipping empty ones."""
    return "/".join(p.strip("/") for p in parts if p and p.strip("/"))


def _split(rel: str) -> tuple[str, str]:
    parent, _, name = rel.rpartition("/")
    return parent, name


class ArtifactStore:
    """Read and write artifacts under one root.

    Args:
        root: a local directory (absolute or relative to the working directory) or any URI that
            ``pyarrow.fs.FileSystem.from_uri`` accepts (``file:///data/run``, ``s3://bucket/prefix``, options such
            as ``?endpoint_override=host:port&scheme=http`` after the path; credentials come from the environment
            and a URI carrying them is refused: ``storage.uris``). With ``filesystem`` given, ``root`` is a path
            inside that filesystem (may be ``""``).
        filesystem: an explicit ``pyarrow.fs.FileSystem`` (e.g. a ``SubTreeFileSystem``); optional.
    """

    def __init__(self, root: str | os.PathLike[str], filesystem: pafs.FileSystem | None = None) -> None:
        root = os.fspath(root)
        if filesystem is not None:
            fs, base, display = filesystem, root, f"{filesystem.type_name}:{root}"
        elif is_uri(root):
            reject_credentials(root)
            fs, base = pafs.FileSystem.from_uri(root)
            display = root
        else:
            base = os.path.abspath(root)
            fs, display = pafs.LocalFileSystem(), base
        self._fs: pafs.FileSystem = fs
        self._base = base.rstrip("/") if base not in ("", "/") else base
        path, query = split_query(display)
        self._display = (path.rstrip("/") if path != "/" else path) + query
        self._renames_atomically = _local_base(fs) is not None

    def __repr__(self) -> str:
        return f"ArtifactStore({self._display!r})"

    # ----------------------------------------------------------------- addressing
    @property
    def root(self) -> str:
        """The root as given (local roots made absolute)."""
        return self._display

    @property
    def filesystem(self) -> pafs.FileSystem:
        return self._fs

    @property
    def renames_atomically(self) -> bool:
        """True on local filesystems (atomic ``rename``), False on object stores."""
        return self._renames_atomically

    def uri(self, relpath: str = "") -> str:
        """Location of ``relpath``: the root URI or absolute local path joined with it (a URI's options kept last,
        so ``ArtifactStore(store.uri(rel))`` opens ``rel`` as a store; never carries credentials)."""
        return join_uri(self._display, normalize_relpath(relpath, allow_root=True))

    def _path(self, rel: str) -> str:
        """Filesystem path of a normalised relative path."""
        if not self._base:
            return rel
        if not rel:
            return self._base
        return f"{self._base}/{rel}" if self._base != "/" else f"/{rel}"

    def _info(self, rel: str) -> pafs.FileInfo:
        return self._fs.get_file_info(self._path(rel))

    # ----------------------------------------------------------------- queries
    def exists(self, relpath: str) -> bool:
        """Whether a file or directory exists at ``relpath``."""
        return self._info(normalize_relpath(relpath, allow_root=True)).type != pafs.FileType.NotFound

    def is_dir(self, relpath: str) -> bool:
        return self._info(normalize_relpath(relpath, allow_root=True)).type == pafs.FileType.Directory

    def size(self, relpath: str) -> int:
        """Size in bytes of the file at ``relpath``."""
        rel = normalize_relpath(relpath)
        info = self._info(rel)
        if info.type != pafs.FileType.File:
            raise FileNotFoundError(f"{self.uri(rel)}: no such file")
        return int(info.size)

    def listdir(self, relpath: str = "") -> list[str]:
        """Sorted names of the direct children of directory ``relpath`` (``[]`` when it is absent)."""
        rel = normalize_relpath(relpath, allow_root=True)
        if self._info(rel).type != pafs.FileType.Directory:
            return []
        selector = pafs.FileSelector(self._path(rel), recursive=False, allow_not_found=True)
        return sorted(info.base_name for info in self._fs.get_file_info(selector))

    def walk(self, relpath: str = "") -> list[str]:
        """Sorted paths, relative to ``relpath``, of every file below directory ``relpath``."""
        return list(self.file_sizes(relpath))

    def file_sizes(self, relpath: str = "") -> dict[str, int]:
        """``{path relative to relpath: bytes}`` of every file below directory ``relpath``, sorted by path, from one
        recursive listing (``{}`` when it is absent)."""
        rel = normalize_relpath(relpath, allow_root=True)
        if self._info(rel).type != pafs.FileType.Directory:
            return {}
        prefix = self._path(rel).rstrip("/") + "/" if self._path(rel) else ""
        selector = pafs.FileSelector(self._path(rel), recursive=True, allow_not_found=True)
        files = {(i.path[len(prefix):] if i.path.startswith(prefix) else i.path): int(i.size or 0)
                 for i in self._fs.get_file_info(selector) if i.type == pafs.FileType.File}
        return dict(sorted(files.items()))

    # ----------------------------------------------------------------- bytes
    def open_input(self, relpath: str) -> pa.NativeFile:
        """Random-access input file; the caller closes it (``with store.open_input(p) as f``).

        Raises:
            FileNotFoundError: naming the artifact URI.
        """
        rel = normalize_relpath(relpath)
        try:
            return self._fs.open_input_file(self._path(rel))
        except OSError as exc:
            if self._info(rel).type == pafs.FileType.NotFound:
                raise FileNotFoundError(f"{self.uri(rel)}: no such artifact") from exc
            raise

    @contextmanager
    def open_output(self, relpath: str) -> Iterator[pa.NativeFile]:
        """Writable stream whose content appears at ``relpath`` atomically when the block succeeds.

        Nothing is visible at ``relpath`` (and no temporary is left) when the block raises.
        """
        rel = normalize_relpath(relpath)
        path = self._path(rel)
        parent, _ = _split(rel)
        self._fs.create_dir(self._path(parent), recursive=True)  # object stores: cheap or a no-op
        if self._renames_atomically:
            tmp = f"{path}{TMP_TAG}{uuid.uuid4().hex}"
            try:
                with self._fs.open_output_stream(tmp, compression=None) as out:
                    yield out
                self._fs.move(tmp, path)
            except BaseException as exc:
                _delete_file_quietly(self._fs, tmp)
                self._raise_if_unwritable(exc, rel)
                raise
        else:
            buffer = pa.BufferOutputStream()
            yield buffer
            data = buffer.getvalue()
            with self._fs.open_output_stream(path, compression=None) as out:  # one PUT: atomic
                out.write(data)
        logger.debug("wrote %s", self.uri(rel))

    def read_bytes(self, relpath: str) -> bytes:
        with self.open_input(relpath) as f:
            return f.read()

    def write_bytes(self, relpath: str, data: bytes) -> None:
        """Write ``data`` to ``relpath`` atomically (replacing an older version)."""
        with self.open_output(relpath) as out:
            out.write(data)

    # ----------------------------------------------------------------- structured
    def read_json(self, relpath: str) -> Any:
        """Parsed JSON of ``relpath``; ``CorruptArtifactError`` naming the file when it is not JSON."""
        raw = self.read_bytes(relpath)
        try:
            return json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise CorruptArtifactError(f"{self.uri(relpath)}: not valid JSON ({exc})") from exc

    def write_json(self, relpath: str, value: Any) -> None:
        """Write ``value`` as indented, key-sorted UTF-8 JSON, atomically."""
        text = json.dumps(value, indent=2, sort_keys=True, ensure_ascii=False)
        self.write_bytes(relpath, (text + "\n").encode("utf-8"))

    def write_table(self, relpath: str, table: pa.Table, schema: pa.Schema) -> None:
        """Validate ``table`` against ``schema`` and write it as Parquet with the schema metadata, atomically."""
        source = self.uri(relpath)
        table = parquet_io.conform(table, schema, source)
        with self.open_output(relpath) as out:
            parquet_io.write_parquet(out, table)

    def read_table(self, relpath: str, schema: pa.Schema | str) -> pa.Table:
        """Read and validate a Parquet table.

        Args:
            schema: the expected ``pa.Schema``, or a table name from ``storage.schemas`` (dims such
                as the Gaussian feature width are then taken from the file metadata).

        Raises:
            FileNotFoundError, CorruptArtifactError, SchemaError: each naming the file.
        """
        with self.open_input(relpath) as f:
            return parquet_io.read_parquet(f, schema, self.uri(relpath))

    # ----------------------------------------------------------------- deletion
    def delete(self, relpath: str) -> bool:
        """Delete a file or a directory tree; returns False when nothing was there."""
        rel = normalize_relpath(relpath)
        kind = self._info(rel).type
        if kind == pafs.FileType.NotFound:
            return False
        if kind == pafs.FileType.Directory:
            self._fs.delete_dir(self._path(rel))
        else:
            self._fs.delete_file(self._path(rel))
        logger.debug("deleted %s", self.uri(rel))
        return True

    def _delete_quietly(self, rel: str) -> None:
        try:
            self.delete(rel)
        except OSError as exc:  # cleanup must not mask the original error
            logger.warning("could not remove temporary %s: %s", self.uri(rel), exc)

    # ----------------------------------------------------------------- groups
    @contextmanager
    def staged_directory(self, relpath: str) -> Iterator[str]:
        """Write a group of files atomically; yields the relative path of a temporary directory.

        Write every file of the group under the yielded path. When the block succeeds the directory
        replaces ``relpath`` (see the module docstring for the guarantees per filesystem); when it
        raises, the temporary directory is removed and ``relpath`` is untouched.

        Example::

            with store.staged_directory("logs/seq0") as tmp:
                store.write_bytes(f"{tmp}/a.bin", data)
        """
        rel = normalize_relpath(relpath)
        parent, name = _split(rel)
        tag = uuid.uuid4().hex
        tmp_rel = join_relpath(parent, f".{name}{TMP_TAG}{tag}")
        if self._renames_atomically:
            with self._commit_lock(rel):
                self._recover_interrupted_swap(parent, name)
        self._fs.create_dir(self._path(tmp_rel), recursive=True)
        try:
            yield tmp_rel
            if self._renames_atomically:
                with self._commit_lock(rel):
                    self._recover_interrupted_swap(parent, name)
                    self._swap_into_place(tmp_rel, rel, join_relpath(parent, f".{name}{OLD_TAG}{tag}"))
            else:
                self._copy_into_place(tmp_rel, rel)
        except BaseException as exc:
            self._delete_quietly(tmp_rel)
            self._raise_if_unwritable(exc, rel)
            raise
        logger.debug("committed %s", self.uri(rel))

    def _commit_lock(self, rel: str) -> Any:
        """The exclusive lock of group ``rel``'s commits: ``.locks/<hash of rel>`` (one file per group, kept)."""
        return self.exclusive(join_relpath(LOCKS_DIR, hashlib.sha256(rel.encode("utf-8")).hexdigest()[:32]))

    def _swap_into_place(self, tmp_rel: str, rel: str, old_rel: str) -> None:
        """Local commit: rename the old version aside, rename the new one in, delete the old one."""
        if self._info(rel).type == pafs.FileType.NotFound:
            self._fs.move(self._path(tmp_rel), self._path(rel))
            return
        self._fs.move(self._path(rel), self._path(old_rel))
        try:
            self._fs.move(self._path(tmp_rel), self._path(rel))
        except BaseException:
            self._fs.move(self._path(old_rel), self._path(rel))
            raise
        self._delete_quietly(old_rel)

    def _recover_interrupted_swap(self, parent: str, name: str) -> None:
        """Undo a swap interrupted between its two renames (old version aside, new one not in)."""
        aside = [c for c in self.listdir(parent) if c.startswith(f".{name}{OLD_TAG}")]
        if not aside:
            return
        rel = join_relpath(parent, name)
        if self._info(rel).type == pafs.FileType.NotFound:
            newest = max(aside, key=lambda c: self._info(join_relpath(parent, c)).mtime_ns or 0)
            logger.warning("restoring %s from interrupted swap %s", self.uri(rel), newest)
            self._fs.move(self._path(join_relpath(parent, newest)), self._path(rel))
            aside.remove(newest)
        for stale in aside:
            self._delete_quietly(join_relpath(parent, stale))

    def _copy_into_place(self, tmp_rel: str, rel: str) -> None:
        """Object-store commit: copy objects marker-last, then drop files of the old version."""
        new_files = self.walk(tmp_rel)
        old_files = self.walk(rel)
        for f in old_files:
            if _is_marker(f):
                self._fs.delete_file(self._path(join_relpath(rel, f)))
        for parent in sorted({_split(join_relpath(rel, f))[0] for f in new_files}):
            self._fs.create_dir(self._path(parent), recursive=True)
        for f in sorted(new_files, key=_is_marker):
            self._fs.copy_file(self._path(join_relpath(tmp_rel, f)), self._path(join_relpath(rel, f)))
        for f in set(old_files) - set(new_files):
            if not _is_marker(f):
                self._fs.delete_file(self._path(join_relpath(rel, f)))
        self._delete_quietly(tmp_rel)

    # ----------------------------------------------------------------- writability
    def _raise_if_unwritable(self, exc: BaseException, rel: str) -> None:
        """Raise ``StoreNotWritableError`` (from ``exc``) naming ``rel`` and the store when ``exc`` is an ``OSError``
        whose ``errno`` says the store cannot be written (``UNWRITABLE_REASONS``); else return."""
        if isinstance(exc, StoreNotWritableError) or not isinstance(exc, OSError):
            return
        reason = UNWRITABLE_REASONS.get(exc.errno or -1)
        if reason is not None:
            raise StoreNotWritableError(f"{self.uri(rel)}: cannot write to the store {self.root}: {reason} "
                                        f"({exc.strerror or exc})") from exc

    def check_writable(self) -> None:
        """Write and delete a small hidden probe file at the root (creating the root when it is missing).

        Raises:
            StoreNotWritableError: the store cannot be written, naming it and why (disk full, read-only, permission
                denied, the root or a parent is a file).
        """
        probe = f".write-probe{TMP_TAG}{uuid.uuid4().hex}"
        try:
            self._fs.create_dir(self._path(""), recursive=True)
            self.write_bytes(probe, b"probe\n")
        except OSError as exc:
            self._raise_if_unwritable(exc, probe)
            raise
        self._delete_quietly(probe)

    # ----------------------------------------------------------------- read-modify-write
    @contextmanager
    def exclusive(self, relpath: str) -> Iterator[None]:
        """Hold an exclusive advisory lock on ``relpath`` while the block runs (for read-modify-write of
        one artifact, e.g. appending rows to a table).

        Locally this is ``flock`` on a hidden ``.<name>.lock`` sibling, which serialises the processes of
        one machine (Ray workers included). Object stores have no locks: there the block only holds a lock of
        this process (its threads, e.g. the thread runner's workers, take turns), and between processes the
        last writer wins: give concurrent writers there artifacts of their own.
        """
        rel = normalize_relpath(relpath)
        parent, name = _split(rel)
        lock_rel = join_relpath(parent, f".{name}.lock")
        os_path = self._os_path(lock_rel)
        if os_path is None:
            with _process_lock(self.uri(rel)):
                yield
            return
        self._fs.create_dir(self._path(parent), recursive=True)
        with open(os_path, "a+b") as handle:
            fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(handle.fileno(), fcntl.LOCK_UN)

    # ----------------------------------------------------------------- local files for C libraries
    @contextmanager
    def local_path_for_write(self, relpath: str) -> Iterator[str]:
        """A local OS path to write ``relpath`` to (for libraries such as OpenImageIO).

        Locally this is a temporary sibling renamed over ``relpath`` when the block succeeds; on
        object stores a file in a local temporary directory uploaded as one PUT afterwards.
        """
        rel = normalize_relpath(relpath)
        os_path = self._os_path(rel)
        if os_path is None:
            with tempfile.TemporaryDirectory(prefix="simsplat-") as tmpdir:
                local = os.path.join(tmpdir, _split(rel)[1])
                yield local
                with open(local, "rb") as f:
                    self.write_bytes(rel, f.read())
            return
        self._fs.create_dir(self._path(_split(rel)[0]), recursive=True)
        suffix = f"{TMP_TAG}{uuid.uuid4().hex}"
        try:
            yield os_path + suffix
            self._fs.move(self._path(rel) + suffix, self._path(rel))
        except BaseException as exc:
            _delete_file_quietly(self._fs, self._path(rel) + suffix)
            self._raise_if_unwritable(exc, rel)
            raise
        logger.debug("wrote %s", self.uri(rel))

    @contextmanager
    def local_path_for_read(self, relpath: str) -> Iterator[str]:
        """A local OS path holding the bytes of ``relpath`` (a downloaded copy on object stores)."""
        rel = normalize_relpath(relpath)
        os_path = self._os_path(rel)
        if os_path is not None:
            if self._info(rel).type != pafs.FileType.File:
                raise FileNotFoundError(f"{self.uri(rel)}: no such artifact")
            yield os_path
            return
        data = self.read_bytes(rel)
        with tempfile.TemporaryDirectory(prefix="simsplat-") as tmpdir:
            local = os.path.join(tmpdir, _split(rel)[1])
            with open(local, "wb") as f:
                f.write(data)
            yield local

    def _os_path(self, rel: str) -> str | None:
        """OS path of ``rel`` when the filesystem is local, else ``None``."""
        local = _local_base(self._fs)
        if local is None:
            return None
        return os.path.join(local, self._path(rel)) if local else self._path(rel)


_PROCESS_LOCKS: dict[str, threading.Lock] = {}
_PROCESS_LOCKS_GUARD = threading.Lock()


def _process_lock(key: str) -> threading.Lock:
    """The lock of this process for the artifact ``key`` (one per key, made on first use)."""
    with _PROCESS_LOCKS_GUARD:
        return _PROCESS_LOCKS.setdefault(key, threading.Lock())


def _is_marker(relpath: str) -> bool:
    return _split(relpath)[1].startswith(MARKER_PREFIX)


def _local_base(fs: pafs.FileSystem) -> str | None:
    """OS directory that filesystem paths are relative to (``""`` for plain local), or ``None``."""
    if isinstance(fs, pafs.LocalFileSystem):
        return ""
    if isinstance(fs, pafs.SubTreeFileSystem):
        inner = _local_base(fs.base_fs)
        if inner is None:
            return None
        return os.path.join(inner, fs.base_path) if inner else fs.base_path
    return None


def _delete_file_quietly(fs: pafs.FileSystem, path: str) -> None:
    try:
        if fs.get_file_info(path).type == pafs.FileType.File:
            fs.delete_file(path)
    except OSError as exc:
        logger.warning("could not remove temporary %s: %s", path, exc)
