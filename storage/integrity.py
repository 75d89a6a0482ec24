"""Integrity of a completed artifact directory: what its manifest records at write time, checked before reuse.

``seal`` runs when a stage marks its staged output done (``storage.markers.mark_done``) and adds to the manifest::

    "integrity": {
        "files": {"tables/x.parquet": {"bytes": 1234, "sha256": "..."}, "renders/a.exr": {"bytes": 9}, ...},
        "manifest_sha256": "...",      # SHA-256 of the manifest itself, this field left out
    }

Every file of the directory but the marker (and hidden temporaries) is listed with its size; files up to
``CHECKSUM_MAX_BYTES`` also get a SHA-256 (hashed once, right after they were written). ``check`` compares a stored
directory with its manifest and returns one line per disagreement, each naming the file:

* the manifest's own digest (an edited or damaged manifest: a count or checksum changed by hand);
* every recorded file present with its recorded size (one recursive listing: truncated or missing files);
* the row count of every table the manifest counts (``tables.<name>.rows``) against ``<name>.parquet``'s footer;
* with ``checksums=True``, the SHA-256 of every file that has one recorded (bytes overwritten in place).

What is cheap: the first three read metadata only (a listing and a few Parquet footers). Checksums read the
bytes of the small files only; a file above ``CHECKSUM_MAX_BYTES`` (full-resolution camera EXRs, large Gaussian
tables) is checked by size, and damage inside it surfaces when it is decoded (``CorruptArtifactError`` naming it).

Manifests written before this module existed have no ``integrity`` entry: they are checked by what they record,
the size and row count of each table in ``tables`` (logs, scenes, language scenes); other files go unchecked.
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
from collections.abc import Mapping
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from storage.errors import CorruptArtifactError
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

#: Manifest key holding the file records and the manifest's own digest.
INTEGRITY_KEY = "integrity"
#: Files up to this size (bytes) get a SHA-256 at write time and have it verified before reuse.
CHECKSUM_MAX_BYTES = 8 * 2**20
_CHUNK_BYTES = 2**20


def file_sha256(store: ArtifactStore, relpath: str) -> str:
    """Hex SHA-256 of the bytes of ``relpath`` (read in 1 MiB chunks)."""
    digest = hashlib.sha256()
    with store.open_input(relpath) as f:
        while chunk := f.read(_CHUNK_BYTES):
            digest.update(chunk)
    return digest.hexdigest()


def manifest_sha256(manifest: Mapping[str, Any]) -> str:
    """SHA-256 of a manifest's canonical JSON, ``integrity.manifest_sha256`` left out."""
    body = copy.deepcopy(dict(manifest))
    body.get(INTEGRITY_KEY, {}).pop("manifest_sha256", None)
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def seal(store: ArtifactStore, directory: str, manifest: Mapping[str, Any], exclude: tuple[str, ...] = ()
         ) -> dict[str, Any]:
    """``manifest`` with its ``integrity`` entry: the size (and, up to ``CHECKSUM_MAX_BYTES``, the SHA-256) of every
    file under ``directory`` but ``exclude`` (relative names), then the manifest's own digest.

    Raises:
        ValueError: ``manifest`` already uses the reserved ``integrity`` key.
    """
    if INTEGRITY_KEY in manifest:
        raise ValueError(f"manifest key {INTEGRITY_KEY!r} is reserved for storage.integrity")
    files: dict[str, dict[str, Any]] = {}
    for name, size in store.file_sizes(directory).items():
        if name in exclude or name.rpartition("/")[2].startswith("."):  # hidden: temporaries, lock files
            continue
        record: dict[str, Any] = {"bytes": size}
        if size <= CHECKSUM_MAX_BYTES:
            record["sha256"] = file_sha256(store, join_relpath(directory, name))
        files[name] = record
    # as it will read back (JSON: int keys become strings, tuples lists), so the digest matches the stored manifest
    sealed = json.loads(json.dumps({**manifest, INTEGRITY_KEY: {"files": files}}, allow_nan=True))
    sealed[INTEGRITY_KEY]["manifest_sha256"] = manifest_sha256(sealed)
    return sealed


def check(store: ArtifactStore, directory: str, manifest: Mapping[str, Any], manifest_name: str, *,
          checksums: bool = True) -> list[str]:
    """Where the stored ``directory`` disagrees with its ``manifest`` (module docstring), one line per file: ``[]``
    when it is intact. ``manifest_name`` is the manifest's file name inside ``directory`` (named in its line)."""
    problems: list[str] = []
    integrity = manifest.get(INTEGRITY_KEY)
    sizes = store.file_sizes(directory)
    if isinstance(integrity, Mapping):
        recorded = integrity.get("manifest_sha256")
        if recorded != manifest_sha256(manifest):
            problems.append(f"{store.uri(join_relpath(directory, manifest_name))}: the manifest does not match its "
                            f"recorded sha256 (edited or damaged)")
        for name, record in sorted(dict(integrity.get("files", {})).items()):
            problems += _file_problems(store, directory, name, record, sizes, checksums)
    problems += _table_problems(store, directory, manifest, sizes, legacy=not isinstance(integrity, Mapping))
    return problems


def _file_problems(store: ArtifactStore, directory: str, name: str, record: Mapping[str, Any],
                   sizes: Mapping[str, int], checksums: bool) -> list[str]:
    uri = store.uri(join_relpath(directory, name))
    if name not in sizes:
        return [f"{uri}: missing (the manifest lists it)"]
    if sizes[name] != record.get("bytes"):
        return [f"{uri}: {sizes[name]} bytes, the manifest recorded {record.get('bytes')}"]
    if checksums and "sha256" in record:
        found = file_sha256(store, join_relpath(directory, name))
        if found != record["sha256"]:
            return [f"{uri}: sha256 {found[:12]}..., the manifest recorded {str(record['sha256'])[:12]}..."]
    return []


def _table_problems(store: ArtifactStore, directory: str, manifest: Mapping[str, Any], sizes: Mapping[str, int],
                    *, legacy: bool) -> list[str]:
    """Row counts of the tables a manifest counts (and, for a manifest without ``integrity``, their sizes)."""
    problems = []
    tables = manifest.get("tables")
    for table, stats in (tables.items() if isinstance(tables, Mapping) else ()):
        if not isinstance(stats, Mapping) or "rows" not in stats:
            continue
        name = f"{table}.parquet"
        uri = store.uri(join_relpath(directory, name))
        if name not in sizes:
            problems.append(f"{uri}: missing (the manifest counts {stats['rows']} rows)")
            continue
        if legacy and "bytes" in stats and sizes[name] != stats["bytes"]:
            problems.append(f"{uri}: {sizes[name]} bytes, the manifest recorded {stats['bytes']}")
            continue
        rows = _parquet_rows(store, join_relpath(directory, name))
        if rows is None:
            problems.append(f"{uri}: not a readable Parquet file")
        elif rows != stats["rows"]:
            problems.append(f"{uri}: {rows} rows, the manifest counts {stats['rows']}")
    return problems


def _parquet_rows(store: ArtifactStore, relpath: str) -> int | None:
    """Row count from a Parquet footer, ``None`` when the footer does not decode."""
    try:
        with store.open_input(relpath) as f:
            return int(pq.ParquetFile(f).metadata.num_rows)
    except (pa.ArrowException, OSError):
        return None


def intact(store: ArtifactStore, directory: str, manifest: Mapping[str, Any], manifest_name: str, *,
           checksums: bool = True) -> bool:
    """Whether ``directory`` agrees with its manifest; when not, a warning names every disagreeing file and says the
    artifact will be recomputed (for a stage deciding whether to reuse it)."""
    problems = check(store, directory, manifest, manifest_name, checksums=checksums)
    if problems:
        logger.warning("%s is corrupt and will be recomputed: %s", store.uri(directory), "; ".join(problems))
    return not problems


def require_intact(store: ArtifactStore, directory: str, manifest: Mapping[str, Any], manifest_name: str, *,
                   checksums: bool = False) -> None:
    """Raise when ``directory`` disagrees with its manifest (for readers: by default without checksums, the files
    are about to be decoded anyway).

    Raises:
        CorruptArtifactError: naming every disagreeing file and what disagrees.
    """
    problems = check(store, directory, manifest, manifest_name, checksums=checksums)
    if problems:
        raise CorruptArtifactError(f"{store.uri(directory)} is corrupt: {'; '.join(problems)}")
