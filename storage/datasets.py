"""Exported datasets on disk: immutable shards, a manifest written last, a data card, the store's listing.

    <out>/<name>/manifest.json             what the dataset holds (``DatasetManifest``), rewritten last
    <out>/<name>/DATACARD.md               the data card (Markdown)
    <out>/<name>/womd/<split>/part-<increment>-<k>.tfrecord
    <out>/<name>/scenarionet/<split>/part-<increment>/sd_*.pkl, dataset_summary.pkl, dataset_mapping.pkl
    <out>/<name>/scenarionet/<split>/dataset_summary.pkl, dataset_mapping.pkl   (every part of the split)
    <out>/<name>/parquet/<table>/split=<split>/part-<increment>-<k>.parquet
    <store>/datasets/<name>.json           the store's listing of its exports (where, when, counts)

Shards are never rewritten: an export adds an increment of new shards for the scenarios the manifest does not
hold yet, each shard written atomically (temporary name, then renamed), and the manifest last, so a killed export
leaves shards the manifest does not name, which the next increment (same number) replaces. The index files that
name every shard (the manifest, ScenarioNet's top-level summary and mapping, the data card, the listing) are
replaced atomically after the shards. Every shard's SHA-256 and size are in the manifest.
"""

from __future__ import annotations

import hashlib
import logging
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import pyarrow as pa

from storage import parquet_io
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

#: Version of ``manifest.json``'s layout.
MANIFEST_VERSION = 1
#: Name of the manifest that marks a folder as an exported dataset.
MANIFEST_NAME = "manifest.json"
DATACARD_NAME = "DATACARD.md"
#: The store's listing of exported datasets.
DATASETS_DIR = "datasets"
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")


class DatasetConflictError(ValueError):
    """The output folder holds something that is not this dataset (another dataset, other files)."""


def check_dataset_name(name: str) -> str:
    """``name`` when it is a safe folder name, else ``ValueError`` naming it."""
    if not _NAME.match(name):
        raise ValueError(f"dataset name {name!r}: use letters, digits, '.', '_' and '-' (at most 128), starting "
                         "with a letter or digit")
    return name


@dataclass(frozen=True)
class ShardRecord:
    """One written shard: path relative to the dataset, bytes, SHA-256, format, split and scenarios in it."""

    path: str
    bytes: int
    sha256: str
    format: str
    split: str
    scenarios: int

    def as_dict(self) -> dict[str, Any]:
        return {"path": self.path, "bytes": self.bytes, "sha256": self.sha256, "format": self.format,
                "split": self.split, "scenarios": self.scenarios}


class DatasetFolder:
    """The folder of one dataset, ``<out>/<name>/`` (module docstring)."""

    def __init__(self, out: ArtifactStore | str, name: str) -> None:
        self.root = out if isinstance(out, ArtifactStore) else ArtifactStore(out)
        self.name = check_dataset_name(name)

    def rel(self, *parts: str) -> str:
        return join_relpath(self.name, *parts)

    def uri(self, *parts: str) -> str:
        return self.root.uri(self.rel(*parts))

    def read_manifest(self) -> dict[str, Any] | None:
        """The manifest, ``None`` for a new dataset. Raises ``DatasetConflictError`` when the folder holds files
        but no manifest (not a dataset: nothing there is overwritten)."""
        rel = self.rel(MANIFEST_NAME)
        if self.root.exists(rel):
            manifest = self.root.read_json(rel)
            if not isinstance(manifest, dict) or manifest.get("kind") != "simsplat-dataset":
                raise DatasetConflictError(f"{self.root.uri(rel)} is not the manifest of a simsplat dataset; "
                                           "choose another --out or --name")
            return manifest
        if self.root.is_dir(self.name) and self.root.walk(self.name):
            raise DatasetConflictError(f"{self.uri()} already holds files but no {MANIFEST_NAME}: not a dataset "
                                       "this command wrote; choose another --out or --name (nothing was written)")
        return None

    def write_shard(self, relpath: str, data: bytes, *, fmt: str, split: str, scenarios: int) -> ShardRecord:
        """Write one shard (``relpath`` inside the dataset) atomically; returns its record."""
        self.root.write_bytes(self.rel(relpath), data)
        return ShardRecord(relpath, len(data), hashlib.sha256(data).hexdigest(), fmt, split, scenarios)

    def write_table_shard(self, relpath: str, table: pa.Table, schema: pa.Schema, *, split: str,
                          scenarios: int) -> ShardRecord:
        """Write one Parquet shard atomically (validated against ``schema``); returns its record."""
        rel = self.rel(relpath)
        sink = pa.BufferOutputStream()
        parquet_io.write_parquet(sink, parquet_io.conform(table, schema, self.root.uri(rel)))
        data = sink.getvalue().to_pybytes()
        self.root.write_bytes(rel, data)
        return ShardRecord(relpath, len(data), hashlib.sha256(data).hexdigest(), "parquet", split, scenarios)

    def write_index(self, relpath: str, data: bytes) -> None:
        """Replace an index file (not a shard) atomically."""
        self.root.write_bytes(self.rel(relpath), data)

    def read_index(self, relpath: str) -> bytes | None:
        rel = self.rel(relpath)
        return self.root.read_bytes(rel) if self.root.exists(rel) else None

    def write_manifest(self, manifest: Mapping[str, Any], datacard: str) -> None:
        """The data card, then the manifest (last: it is what makes the increment part of the dataset)."""
        self.root.write_bytes(self.rel(DATACARD_NAME), datacard.encode("utf-8"))
        self.root.write_json(self.rel(MANIFEST_NAME), dict(manifest))


def dataset_listing_relpath(name: str) -> str:
    return join_relpath(DATASETS_DIR, f"{check_dataset_name(name)}.json")


def write_dataset_listing(store: ArtifactStore, name: str, entry: Mapping[str, Any]) -> None:
    """Record in the store's ``datasets/`` listing where dataset ``name`` is and what it holds."""
    store.write_json(dataset_listing_relpath(name), dict(entry))


def list_datasets(store: ArtifactStore) -> list[dict[str, Any]]:
    """Every entry of the store's ``datasets/`` listing, by name."""
    if not store.is_dir(DATASETS_DIR):
        return []
    out = []
    for entry in sorted(store.listdir(DATASETS_DIR)):
        if entry.endswith(".json"):
            out.append(store.read_json(join_relpath(DATASETS_DIR, entry)))
    return out
