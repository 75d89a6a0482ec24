"""Local copies of object-store folders, for readers that need local files (log loaders and their detection).

The log loaders (``simsplat_core.data``) read local files, and deciding which source a landing log belongs to reads
its first bytes. A landing location in an object store is therefore read through a local copy:

* ``mirror_folder`` keeps a *mirror* of a whole landing prefix in a local folder: objects that are new or whose
  size or modification time changed are downloaded (each to a hidden temporary renamed into place, so a killed
  download leaves nothing that looks complete), files whose object is gone are removed, unchanged ones are kept.
  Every mirrored file gets its object's modification time, so a key computed from the mirror's sizes and times
  (``tasks.landing.landing_key``) is the same on every machine and after the mirror is rebuilt from scratch. A
  second scan of an unchanged landing downloads nothing.
* ``fetched`` downloads one log (an object, or every object under a folder prefix) into a temporary folder for
  the time a loader reads it: what an ingest task on any worker does, so it needs no mirror of its own.

Hidden names (``.name``) are skipped, as in a local landing folder.
"""

from __future__ import annotations

import logging
import os
import shutil
import tempfile
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pyarrow.fs as pafs

from storage.keys import content_key
from storage.store import TMP_TAG
from storage.uris import is_uri, reject_credentials

logger = logging.getLogger(__name__)

#: Environment variable naming the folder that holds landing mirrors (default: the system temporary folder).
MIRROR_DIR_ENV = "SIMSPLAT_LANDING_MIRROR"
_COPY_CHUNK = 8 << 20
#: URI schemes of ``pyarrow``'s local filesystem.
LOCAL_SCHEMES = frozenset({"file", "local"})


@dataclass(frozen=True)
class RemoteFile:
    """One object under a remote folder.

    Attributes:
        relpath: its path below the folder (``/`` separators).
        size: bytes.
        mtime_ns: its modification time (ns since the epoch; object stores keep whole seconds or milliseconds).
    """

    relpath: str
    size: int
    mtime_ns: int


def is_remote(location: str) -> bool:
    """Whether ``location`` is a URI of a filesystem other than the local one (an object store)."""
    return is_uri(location) and location.split("://", 1)[0].lower() not in LOCAL_SCHEMES


def _open(uri: str) -> tuple[pafs.FileSystem, str]:
    reject_credentials(uri)
    filesystem, path = pafs.FileSystem.from_uri(uri)
    return filesystem, path.rstrip("/")


def _hidden(relpath: str) -> bool:
    return any(part.startswith(".") for part in relpath.split("/"))


def list_remote_files(uri: str) -> list[RemoteFile]:
    """Every non-hidden object below the folder ``uri``, sorted by path (stat-only: one listing).

    Raises:
        FileNotFoundError: ``uri`` is not a folder (naming it).
    """
    filesystem, base = _open(uri)
    if filesystem.get_file_info(base).type != pafs.FileType.Directory:
        raise FileNotFoundError(f"{uri}: no such folder")
    found = []
    for info in filesystem.get_file_info(pafs.FileSelector(base, recursive=True)):
        relpath = info.path[len(base) + 1:]
        if info.type == pafs.FileType.File and not _hidden(relpath):
            found.append(RemoteFile(relpath, int(info.size), int(info.mtime_ns or 0)))
    return sorted(found, key=lambda f: f.relpath)


def default_mirror_dir(uri: str) -> Path:
    """Where the mirror of ``uri`` lives: ``$SIMSPLAT_LANDING_MIRROR`` (default: the system temporary folder)
    ``/simsplat-landing/<key of the URI>``."""
    root = Path(os.environ.get(MIRROR_DIR_ENV) or tempfile.gettempdir())
    return root / "simsplat-landing" / content_key("landing-mirror", uri)[:16]


def _download(filesystem: pafs.FileSystem, path: str, target: Path, mtime_ns: int) -> None:
    """Copy the object at ``path`` to ``target`` through a hidden temporary, with the object's modification time."""
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}{TMP_TAG}{uuid.uuid4().hex}")
    try:
        with filesystem.open_input_stream(path) as source, open(tmp, "wb") as out:
            while chunk := source.read(_COPY_CHUNK):
                out.write(chunk)
        os.utime(tmp, ns=(mtime_ns, mtime_ns))
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _is_current(local: Path, remote: RemoteFile) -> bool:
    if not local.is_file():
        return False
    stat = local.stat()
    return stat.st_size == remote.size and stat.st_mtime_ns == remote.mtime_ns


def mirror_folder(uri: str, local: Path) -> Path:
    """Bring the local mirror ``local`` of the folder ``uri`` up to date (module docstring); returns ``local``.

    Raises:
        FileNotFoundError: ``uri`` is not a folder.
    """
    filesystem, base = _open(uri)
    remote = list_remote_files(uri)
    local.mkdir(parents=True, exist_ok=True)
    fetched = 0
    for file in remote:
        target = local.joinpath(*file.relpath.split("/"))
        if not _is_current(target, file):
            _download(filesystem, f"{base}/{file.relpath}", target, file.mtime_ns)
            fetched += 1
    wanted = {local.joinpath(*f.relpath.split("/")) for f in remote}
    for path in sorted(local.rglob("*"), reverse=True):
        if path.is_file() and path not in wanted:
            path.unlink()
        elif path.is_dir() and not any(path.iterdir()):
            path.rmdir()
    logger.info("landing mirror %s: %d object(s), %d downloaded", local, len(remote), fetched)
    return local


@contextmanager
def fetched(uri: str) -> Iterator[Path]:
    """A local copy of the object or folder at ``uri`` (same base name) in a temporary folder removed afterwards.

    Raises:
        FileNotFoundError: nothing at ``uri``.
    """
    filesystem, base = _open(uri)
    info = filesystem.get_file_info(base)
    name = base.rsplit("/", 1)[-1] or "log"
    tmpdir = Path(tempfile.mkdtemp(prefix="simsplat-fetch-"))
    try:
        target = tmpdir / name
        if info.type == pafs.FileType.File:
            _download(filesystem, base, target, int(info.mtime_ns or 0))
        elif info.type == pafs.FileType.Directory:
            for file in list_remote_files(uri):
                _download(filesystem, f"{base}/{file.relpath}", target.joinpath(*file.relpath.split("/")),
                          file.mtime_ns)
        else:
            raise FileNotFoundError(f"{uri}: no such object or folder")
        yield target
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
