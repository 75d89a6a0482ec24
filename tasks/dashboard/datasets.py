"""The datasets pages: every dataset the store's listing names (``storage.datasets.list_datasets``), its manifest
(counts, splits, formats, shards with SHA-256 and sizes, filters, code and schema versions, notes) and data card,
checked against the files on disk.

    views = read_datasets(store)                      # one summary per listed dataset
    view = read_dataset(store, "d1", verify=False)    # the manifest, its shards and the count checks

Checks are cheap by default: every shard the manifest names must be there with the size it records, and the
counts must agree with each other (scenarios, splits, increments, the scenarios each format's shards hold, the
listing). Hashing every shard (``verify=True``, the page's ``?verify=1``) reads every byte, so it runs only when
asked. Reads only: a dataset folder outside the store (``simsplat export --out``) is read where the listing says
it is.
"""

from __future__ import annotations

import functools
import hashlib
import logging
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from storage.datasets import DATACARD_NAME, DatasetFolder, list_datasets
from storage.store import ArtifactStore
from storage.uris import split_name
from tasks.dashboard.sections import READ_ERRORS, Section, section

logger = logging.getLogger(__name__)

#: Bytes read at a time when hashing a shard.
HASH_CHUNK = 1 << 20
#: Scenarios the dataset page lists at most (the manifest holds them all).
MAX_SCENARIOS = 500

#: Shard states: present with the recorded size (hash not checked), hashed and equal, absent, other size, other hash.
SHARD_STATES: tuple[str, ...] = ("ok", "verified", "missing", "size", "checksum")


@dataclass(frozen=True)
class ShardCheck:
    """One shard of the manifest against the file on disk.

    Attributes:
        path: inside the dataset; format, split, scenarios, bytes, sha256: as the manifest records them.
        increment: the increment that wrote it.
        state: one of :data:`SHARD_STATES`; found_bytes: the file's size (``None`` when absent).
    """

    path: str
    format: str
    split: str
    scenarios: int
    bytes: int
    sha256: str
    increment: int
    state: str
    found_bytes: int | None

    @property
    def ok(self) -> bool:
        return self.state in ("ok", "verified")


@dataclass(frozen=True)
class CountCheck:
    """Two counts that must agree: what is counted, the count declared and the count found."""

    what: str
    declared: int
    found: int

    @property
    def ok(self) -> bool:
        return self.declared == self.found


@dataclass(frozen=True)
class ScenarioRow:
    """One exported scenario as the manifest lists it."""

    scenario_id: str
    split: str
    category: str
    seq_id: str
    log_source: str
    tracks: int
    increment: int
    notes: str


@dataclass(frozen=True)
class DatasetSummary:
    """One listed dataset at a glance: where it is, what it holds and how many checks fail (``problems``)."""

    name: str
    uri: str
    updated: str
    scenarios: int
    formats: tuple[str, ...]
    increments: int
    by_split: dict[str, int]
    shards: int
    bytes: int
    problems: int


@dataclass(frozen=True)
class ManifestView:
    """A dataset's manifest as shown, checked against its files.

    Attributes:
        created, updated, code_version, manifest_version, source_store: from the manifest.
        counts: the manifest's counts (scenarios, by split, category, log source, agent type, source log).
        splits: the split ratios; formats; schema_versions; filters; layout; licences: from the manifest.
        left_out: scenarios left out after re-validation, with the reason.
        increments: ``(index, scenarios, seconds, time, shards, bytes)`` per increment.
        shards: every shard against the disk; count_checks: the counts that must agree.
        verified: whether every shard was hashed.
        scenarios: up to :data:`MAX_SCENARIOS` scenarios; more_scenarios: those left out of the list.
        problems: one line per disagreement (``()``: the manifest matches its files).
    """

    created: str
    updated: str
    code_version: str
    manifest_version: int
    source_store: str
    counts: dict[str, Any]
    splits: dict[str, float]
    formats: tuple[str, ...]
    schema_versions: dict[str, Any]
    filters: dict[str, Any]
    layout: dict[str, Any]
    licences: dict[str, str]
    left_out: dict[str, Any]
    increments: tuple[tuple[int, int, float, str, int, int], ...]
    shards: tuple[ShardCheck, ...]
    count_checks: tuple[CountCheck, ...]
    verified: bool
    scenarios: tuple[ScenarioRow, ...]
    more_scenarios: int
    problems: tuple[str, ...]


@dataclass(frozen=True)
class DatasetView:
    """One dataset's page: its listing entry, its checked manifest and its data card (each may fail alone)."""

    name: str
    uri: str
    listing: dict[str, Any]
    manifest: Section[ManifestView]
    datacard: Section[str]


@dataclass(frozen=True)
class DatasetsView:
    """Every dataset of the store's listing, each summary a section of its own."""

    store: str
    datasets: Section[tuple[Section[DatasetSummary], ...]]


# ----------------------------------------------------------------------------- opening a dataset
def dataset_folder(entry: Mapping[str, Any]) -> DatasetFolder:
    """The folder a listing entry names (its ``uri``, ending in the dataset's name).

    Raises:
        ValueError: the entry has no ``uri`` or ``name``, or its uri does not end in its name (naming both).
    """
    uri, name = str(entry.get("uri", "")), str(entry.get("name", ""))
    parent, last = split_name(uri)
    if not uri or not name or last != name:
        raise ValueError(f"dataset listing entry {name!r}: its uri {uri!r} does not name a folder called {name!r}")
    return DatasetFolder(parent or "/", name)


def _listing(store: ArtifactStore, name: str) -> dict[str, Any] | None:
    for entry in list_datasets(store):
        if isinstance(entry, dict) and entry.get("name") == name:
            return entry
    return None


def _read_manifest(folder: DatasetFolder) -> dict[str, Any]:
    manifest = folder.read_manifest()
    if manifest is None:
        raise FileNotFoundError(f"{folder.uri()}: no manifest.json (the dataset folder is missing or was never "
                                "completed)")
    return manifest


# ----------------------------------------------------------------------------- checks
def _sha256(folder: DatasetFolder, relpath: str) -> str:
    digest = hashlib.sha256()
    with folder.root.open_input(folder.rel(relpath)) as f:
        while chunk := f.read(HASH_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def check_shard(folder: DatasetFolder, record: Mapping[str, Any], increment: int, *, verify: bool) -> ShardCheck:
    """One shard record against the disk: present with its size, and (``verify``) its SHA-256."""
    path = str(record["path"])
    rel = folder.rel(path)
    found = folder.root.size(rel) if folder.root.exists(rel) else None
    if found is None:
        state = "missing"
    elif found != int(record["bytes"]):
        state = "size"
    elif verify:
        state = "verified" if _sha256(folder, path) == record["sha256"] else "checksum"
    else:
        state = "ok"
    return ShardCheck(path, str(record["format"]), str(record["split"]), int(record["scenarios"]),
                      int(record["bytes"]), str(record["sha256"]), increment, state, found)


def _shard_group(shard: ShardCheck) -> str:
    """The shards that together hold every scenario once: a format's (``womd``), or a Parquet table's
    (``parquet/agents``): the path before its split folder."""
    parts = shard.path.split("/")
    for k, part in enumerate(parts):
        if part in (shard.split, f"split={shard.split}"):
            return "/".join(parts[:k]) or shard.format
    return shard.format


def count_checks(manifest: Mapping[str, Any], shards: tuple[ShardCheck, ...],
                 listing: Mapping[str, Any] | None) -> tuple[CountCheck, ...]:
    """The counts of a manifest that must agree with each other, its shards and the store's listing."""
    counts = manifest.get("counts", {})
    total = int(counts.get("scenarios", 0))
    scenarios = manifest.get("scenarios", {})
    checks = [CountCheck("scenarios listed in the manifest", total, len(scenarios)),
              CountCheck("scenarios of the increments", total,
                         sum(int(i.get("scenarios", 0)) for i in manifest.get("increments", [])))]
    by_split = Counter(str(s.get("split")) for s in scenarios.values())
    for split, declared in sorted(counts.get("by_split", {}).items()):
        checks.append(CountCheck(f"scenarios of split {split}", int(declared), by_split.get(split, 0)))
    groups: Counter[str] = Counter()
    for shard in shards:
        groups[_shard_group(shard)] += shard.scenarios
    checks.extend(CountCheck(f"scenarios in the {group} shards", total, n) for group, n in sorted(groups.items()))
    if listing is not None and isinstance(listing.get("counts"), dict):
        checks.append(CountCheck("scenarios in the store's listing", total, int(listing["counts"].get("scenarios", 0))))
    return tuple(checks)


def _problems(shards: tuple[ShardCheck, ...], checks: tuple[CountCheck, ...]) -> tuple[str, ...]:
    said = {"missing": "is missing", "size": "has another size than the manifest records",
            "checksum": "has another SHA-256 than the manifest records"}
    lines = [f"shard {s.path} {said[s.state]}" + (f" ({s.found_bytes} bytes, manifest {s.bytes})"
                                                  if s.state == "size" else "") for s in shards if not s.ok]
    lines += [f"{c.what}: manifest {c.declared}, found {c.found}" for c in checks if not c.ok]
    return tuple(lines)


# ----------------------------------------------------------------------------- the pages
def _scenario_rows(manifest: Mapping[str, Any]) -> list[ScenarioRow]:
    return [ScenarioRow(sid, str(s.get("split", "")), str(s.get("category", "")), str(s.get("seq_id", "")),
                        str(s.get("log_source", "")), int(s.get("tracks", 0)), int(s.get("increment", 0)),
                        str(s.get("notes", "")))
            for sid, s in sorted(manifest.get("scenarios", {}).items())]


def manifest_view(folder: DatasetFolder, manifest: Mapping[str, Any], listing: Mapping[str, Any] | None, *,
                  verify: bool) -> ManifestView:
    """``manifest`` as shown, its shards checked against ``folder`` (hashed when ``verify``)."""
    increments = manifest.get("increments", [])
    shards = tuple(check_shard(folder, s, int(i.get("index", 0)), verify=verify)
                   for i in increments for s in i.get("shards", []))
    checks = count_checks(manifest, shards, listing)
    rows = _scenario_rows(manifest)
    return ManifestView(
        created=str(manifest.get("created", "")), updated=str(manifest.get("updated", "")),
        code_version=str(manifest.get("code_version", "")), manifest_version=int(manifest.get("manifest_version", 0)),
        source_store=str(manifest.get("store", "")), counts=dict(manifest.get("counts", {})),
        splits=dict(manifest.get("splits", {})), formats=tuple(manifest.get("formats", ())),
        schema_versions=dict(manifest.get("schema_versions", {})), filters=dict(manifest.get("filters", {})),
        layout=dict(manifest.get("layout", {})), licences=dict(manifest.get("licences", {})),
        left_out=dict(manifest.get("left_out", {})),
        increments=tuple((int(i.get("index", 0)), int(i.get("scenarios", 0)), float(i.get("seconds", 0.0)),
                          str(i.get("time", "")), len(i.get("shards", [])),
                          sum(int(s.get("bytes", 0)) for s in i.get("shards", []))) for i in increments),
        shards=shards, count_checks=checks, verified=verify, scenarios=tuple(rows[:MAX_SCENARIOS]),
        more_scenarios=max(0, len(rows) - MAX_SCENARIOS), problems=_problems(shards, checks))


def _summary(entry: Mapping[str, Any]) -> DatasetSummary:
    name = str(entry.get("name", ""))
    folder = dataset_folder(entry)
    view = manifest_view(folder, _read_manifest(folder), entry, verify=False)
    return DatasetSummary(name, folder.uri(), view.updated, int(view.counts.get("scenarios", 0)), view.formats,
                          len(view.increments), dict(view.counts.get("by_split", {})), len(view.shards),
                          sum(s.bytes for s in view.shards), len(view.problems))


def _summaries(store: ArtifactStore) -> tuple[Section[DatasetSummary], ...]:
    return tuple(section(f"dataset {entry.get('name', '?')}", functools.partial(_summary, entry))
                 for entry in list_datasets(store))


def read_datasets(store: ArtifactStore) -> DatasetsView:
    """Every listed dataset's summary; a dataset whose folder or manifest cannot be read says so in its place."""
    return DatasetsView(store.uri(), section("datasets", lambda: _summaries(store)))


def read_dataset(store: ArtifactStore, name: str, *, verify: bool = False) -> DatasetView | None:
    """Dataset ``name`` of the store's listing with its checked manifest and data card; ``None`` when the listing
    has no such dataset."""
    try:
        listing = _listing(store, name)
    except READ_ERRORS as exc:
        logger.warning("datasets listing: %s", exc)
        return None
    if listing is None:
        return None
    try:
        folder = dataset_folder(listing)
    except ValueError as exc:
        problem: Section[Any] = Section("dataset folder", error=str(exc))
        return DatasetView(name, str(listing.get("uri", "")), listing, problem, problem)
    manifest = section("manifest", lambda: manifest_view(folder, _read_manifest(folder), listing, verify=verify))
    datacard = section("data card", lambda: folder.root.read_bytes(folder.rel(DATACARD_NAME)).decode("utf-8"))
    return DatasetView(name, folder.uri(), listing, manifest, datacard)


__all__ = ["CountCheck", "DatasetSummary", "DatasetView", "DatasetsView", "ManifestView", "SHARD_STATES",
           "ScenarioRow", "ShardCheck", "check_shard", "count_checks", "dataset_folder", "manifest_view",
           "read_dataset", "read_datasets"]
