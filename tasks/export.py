"""Export a store's scenarios as a dataset for planner training (``simsplat export``, the main flow's export stage).

One call adds one increment to ``<out>/<name>/`` (layout in ``storage.datasets``): the chosen logs or edits
(``tasks.export_inputs``) become ``ExportScenario`` windows (``simsplat_core.export.from_log``), each re-validated
from its exported tracks (``simsplat_core.export.validate``; a failing one is reported and left out unless
``keep_failing``), assigned a split by its source log (a hash of the sequence id, so every variant of a log lands
in the same split and a log's split never changes as the store grows), and the scenarios the manifest does not
hold yet are written in every requested format (``storage.dataset_formats``). Then the manifest (inputs by content
key, filters, counts, shard checksums, schema and code versions), the data card and the store's ``datasets/``
listing. A dataset folder made with other filters, formats, splits or layout is refused: nothing is overwritten.
"""

from __future__ import annotations

import datetime
import hashlib
import logging
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.data.registry import licence_of
from simsplat_core.export.datacard import datacard_markdown
from simsplat_core.export.from_log import export_log_scenarios
from simsplat_core.export.map_features import export_map
from simsplat_core.export.record import ExportScenario
from simsplat_core.export.validate import exported_map_context, revalidate
from simsplat_core.export.windows import ExportLayout
from storage import ArtifactStore
from storage.dataset_formats import FORMATS, format_versions, write_format
from storage.datasets import (
    MANIFEST_VERSION,
    DatasetConflictError,
    DatasetFolder,
    ShardRecord,
    check_dataset_name,
    write_dataset_listing,
)
from storage.edits import edit_dir
from tasks.code_version import code_version
from tasks.export_inputs import ExportFilters, ExportInput, LogCache, group_by_sequence, scenario_source, select_inputs
from tasks.progress import StepProgress, publish_rows
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)

#: ``progress(done, total)`` over the inputs read, then the shards written.
Progress = Callable[[int, int], None]
#: Default dataset folder under a store when no ``--out`` is given.
STORE_DATASETS = "datasets"


def parse_splits(text: str) -> tuple[tuple[str, float], ...]:
    """``"train=0.8,val=0.2"`` -> ``(("train", 0.8), ("val", 0.2))``; fractions must be positive and sum to 1."""
    out: list[tuple[str, float]] = []
    for part in (p.strip() for p in text.split(",") if p.strip()):
        name, sep, value = part.partition("=")
        try:
            fraction = float(value)
        except ValueError:
            fraction = -1.0
        if not sep or not name.strip() or fraction <= 0:
            raise ValueError(f"--split {text!r}: write NAME=FRACTION pairs, e.g. train=0.8,val=0.2 (got {part!r})")
        out.append((check_dataset_name(name.strip()), fraction))
    names = [n for n, _ in out]
    if not out or len(set(names)) != len(names) or abs(sum(f for _, f in out) - 1.0) > 1e-6:
        raise ValueError(f"--split {text!r}: distinct split names whose fractions sum to 1")
    return tuple(out)


def split_of(seq_id: str, splits: Sequence[tuple[str, float]]) -> str:
    """The split of every scenario of log ``seq_id``: a uniform number from the SHA-256 of its id against the
    cumulative fractions (stable across exports and machines)."""
    u = int.from_bytes(hashlib.sha256(seq_id.encode("utf-8")).digest()[:8], "big") / 2.0**64
    edge = 0.0
    for name, fraction in splits:
        edge += fraction
        if u < edge:
            return name
    return splits[-1][0]


@dataclass(frozen=True)
class ExportConfig:
    """What ``export_dataset`` writes.

    Attributes:
        name: the dataset's folder name under ``out``.
        formats: some of ``storage.dataset_formats.FORMATS`` (``womd``, ``scenarionet``, ``parquet``).
        filters: which logs or edits (``tasks.export_inputs.ExportFilters``).
        splits: split name -> fraction of the source logs.
        layout: steps, rate and stride of each scenario (WOMD's 91 steps at 10 Hz by default).
        keep_failing: also export scenarios whose re-validation fails (they are reported either way).
        shard_scenarios: scenarios per TFRecord / Parquet shard.
    """

    name: str = "scenarios"
    formats: tuple[str, ...] = FORMATS
    filters: ExportFilters = field(default_factory=ExportFilters)
    splits: tuple[tuple[str, float], ...] = (("train", 0.8), ("val", 0.2))
    layout: ExportLayout = field(default_factory=ExportLayout)
    keep_failing: bool = False
    shard_scenarios: int = 64

    def __post_init__(self) -> None:
        check_dataset_name(self.name)
        unknown = sorted(set(self.formats) - set(FORMATS))
        if unknown or not self.formats:
            raise ValueError(f"--format {unknown or '(none)'}: choose from {list(FORMATS)}")
        if self.shard_scenarios < 1:
            raise ValueError(f"shard_scenarios must be at least 1, got {self.shard_scenarios}")

    def identity(self) -> dict[str, Any]:
        """What must match for an export to add to an existing dataset."""
        return {"formats": sorted(self.formats), "filters": self.filters.as_dict(),
                "splits": dict(self.splits), "layout": asdict(self.layout)}


@dataclass(frozen=True)
class ExportResult:
    """What one export did.

    Attributes:
        dataset_uri: where the dataset is.
        increment: the increment written (0 when nothing was new).
        new_scenarios: scenario ids written by this export, by split.
        skipped_existing: scenarios already in the dataset.
        left_out: scenario id -> why it was not exported (failed re-validation).
        shards: the shards written.
        counts: the whole dataset's counts (manifest ``counts``).
        seconds: wall time per part (``read``, ``validate``, ``write``, ``total``).
    """

    dataset_uri: str
    increment: int
    new_scenarios: Mapping[str, tuple[str, ...]]
    skipped_existing: int
    left_out: Mapping[str, str]
    shards: tuple[ShardRecord, ...]
    counts: Mapping[str, Any]
    seconds: Mapping[str, float]

    @property
    def written(self) -> int:
        return sum(len(v) for v in self.new_scenarios.values())


def _new_manifest(config: ExportConfig, store: ArtifactStore) -> dict[str, Any]:
    now = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    return {"kind": "simsplat-dataset", "manifest_version": MANIFEST_VERSION, "name": config.name, "created": now,
            "store": store.uri(), **config.identity(), "inputs": {}, "scenarios": {}, "left_out": {},
            "increments": [], "licences": {}}


def _check_same_dataset(manifest: Mapping[str, Any], config: ExportConfig, folder: DatasetFolder) -> None:
    mine = config.identity()
    theirs = {k: manifest.get(k) for k in mine}
    if theirs != mine:
        diff = {k: (theirs[k], mine[k]) for k in mine if theirs[k] != mine[k]}
        raise DatasetConflictError(f"{folder.uri()} holds another dataset (made with {diff}, as (there, asked)); "
                                   "choose another --name or --out, or repeat the same options to add to it")


def _scenario_entry(s: ExportScenario, split: str, item: ExportInput, increment: int) -> dict[str, Any]:
    meta = s.metadata
    return {
        "split": split, "seq_id": item.seq_id, "log_source": meta.get("log_source", ""), "input": item.input_id,
        "category": meta.get("category", "") or ("log" if item.record is None else ""),
        "window": int(meta.get("window", "0")), "tracks": s.num_tracks,
        "agent_types": dict(Counter(s.agent_types)), "increment": increment,
        "track_ids": {o: int(t) for o, t in zip(s.source_object_ids, s.track_ids.tolist())},
        "notes": meta.get("notes", ""),
    }


def _counts(scenarios: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    by: dict[str, Counter[str]] = defaultdict(Counter)
    for entry in scenarios.values():
        by["split"][entry["split"]] += 1
        by["category"][entry["category"]] += 1
        by["source_log"][entry["seq_id"]] += 1
        by["log_source"][entry["log_source"]] += 1
        for kind, n in entry["agent_types"].items():
            by["agent_type"][kind] += n
    return {"scenarios": len(scenarios), **{f"by_{k}": dict(sorted(v.items())) for k, v in sorted(by.items())}}


def _render_refs(store: ArtifactStore, item: ExportInput) -> list[tuple[str, int, str, str]]:
    """(camera, frame, EXR URI, PNG preview URI) of an edit's stored renders ([] for logs and image-less edits)."""
    if item.record is None:
        return []
    rel = edit_dir(item.record.run_id, item.seq_id, item.record.edit_id)
    preview = next((store.uri(f"{rel}/{p}") for p in ("before_after.png", "bev.png") if store.exists(f"{rel}/{p}")), "")
    refs = []
    for path in store.walk(f"{rel}/renders"):
        camera, _, name = path.rpartition("/")
        if name.endswith(".exr") and name[:-4].isdigit():
            refs.append((camera, int(name[:-4]), store.uri(f"{rel}/renders/{path}"), preview))
    return refs


def _collect(store: ArtifactStore, config: ExportConfig, inputs: Sequence[ExportInput], manifest: dict[str, Any],
             progress: Progress | None, seconds: dict[str, float]) -> tuple[dict[str, list[ExportScenario]],
                                                                           dict[str, ExportInput], int, dict[str, str]]:
    """New scenarios by split, the input of each, how many the dataset already had, and those left out."""
    logs = LogCache(store)
    by_split: dict[str, list[ExportScenario]] = defaultdict(list)
    origin: dict[str, ExportInput] = {}
    existing, left_out = 0, {}
    maps: dict[str, Any] = {}
    for k, item in enumerate(inputs):
        t0 = time.perf_counter()
        source = scenario_source(store, logs, item)
        if item.seq_id not in maps:  # one map per log, shared by its edits
            maps[item.seq_id] = export_map(source.log)
        exported_map = maps[item.seq_id]
        scenarios = export_log_scenarios(source, config.layout, exported_map)
        seconds["read"] += time.perf_counter() - t0
        t0 = time.perf_counter()
        map_ctx = exported_map_context(scenarios[0]) if scenarios else None
        for s in scenarios:
            if s.scenario_id in manifest["scenarios"]:
                existing += 1
                continue
            report = revalidate(s, map_ctx)
            if not report.ok:
                reason = "; ".join(report.failures())
                logger.warning("%s fails re-validation: %s%s", s.scenario_id, reason,
                               "" if not config.keep_failing else " (kept: keep_failing)")
                if not config.keep_failing:
                    left_out[s.scenario_id] = reason
                    continue
            by_split[split_of(item.seq_id, config.splits)].append(s)
            origin[s.scenario_id] = item
        seconds["validate"] += time.perf_counter() - t0
        manifest["inputs"][item.input_id] = item.key
        manifest["licences"][source.log.source] = licence_of(source.log.source)
        if progress is not None:
            progress(k + 1, len(inputs))
    return by_split, origin, existing, left_out


def export_dataset(store_root: str, out: str | None = None, config: ExportConfig | None = None,
                   progress: Progress | None = None) -> ExportResult:
    """Add one increment of ``store_root``'s scenarios to ``<out>/<config.name>/`` (module docstring).

    Raises:
        MissingInputError: an empty store, an unknown run, no edit run, or nothing that passes the filters.
        DatasetConflictError: the folder holds another dataset or files that are not a dataset.
        ValueError: bad options (naming the option).
    """
    started = time.perf_counter()
    config = config or ExportConfig()
    store = ArtifactStore(store_root)
    folder = DatasetFolder(out if out is not None else store.uri(STORE_DATASETS), config.name)
    manifest = folder.read_manifest()
    if manifest is not None:
        _check_same_dataset(manifest, config, folder)
    else:
        manifest = _new_manifest(config, store)
    inputs = group_by_sequence(select_inputs(store, config.filters))
    seconds = {"read": 0.0, "validate": 0.0, "write": 0.0}
    by_split, origin, existing, left_out = _collect(store, config, inputs, manifest, progress, seconds)
    increment = len(manifest["increments"]) + 1 if by_split else 0
    if increment == 1 and not manifest["increments"]:  # claim the folder before the first shard lands in it
        folder.write_manifest(manifest, datacard_markdown(manifest))
    shards: list[ShardRecord] = []
    t0 = time.perf_counter()
    for split, scenarios in sorted(by_split.items()):
        refs = {s.scenario_id: _render_refs(store, origin[s.scenario_id]) for s in scenarios}
        for fmt in config.formats:
            shards += write_format(folder, fmt, split, increment, scenarios, config.shard_scenarios, refs)
        for s in scenarios:
            manifest["scenarios"][s.scenario_id] = _scenario_entry(s, split, origin[s.scenario_id], increment)
    seconds["write"] = time.perf_counter() - t0
    manifest["left_out"].update(left_out)
    now = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    if increment:
        manifest["increments"].append({
            "index": increment, "time": now, "scenarios": sum(len(v) for v in by_split.values()),
            "shards": [s.as_dict() for s in shards], "seconds": round(time.perf_counter() - started, 3)})
    manifest.update(updated=now, code_version=code_version(), schema_versions=format_versions(config.formats),
                    counts=_counts(manifest["scenarios"]))
    folder.write_manifest(manifest, datacard_markdown(manifest))
    write_dataset_listing(store, config.name, {
        "name": config.name, "uri": folder.uri(), "updated": now, "counts": manifest["counts"],
        "formats": sorted(config.formats), "increments": len(manifest["increments"])})
    seconds["total"] = time.perf_counter() - started
    new = {split: tuple(s.scenario_id for s in v) for split, v in sorted(by_split.items())}
    logger.info("export %s: %d new scenarios (%d already there, %d left out) in %.1f s", folder.uri(),
                sum(len(v) for v in new.values()), existing, len(left_out), seconds["total"])
    return ExportResult(folder.uri(), increment, new, existing, left_out, tuple(shards), manifest["counts"], seconds)


def export_rows(result: ExportResult) -> list[dict[str, Any]]:
    """One row per split of the dataset: scenarios new in this export and in total (the flow's table artifact)."""
    return [{"dataset": result.dataset_uri, "split": split, "new": len(result.new_scenarios.get(split, ())),
             "total": total, "left_out": len(result.left_out) if k == 0 else 0}
            for k, (split, total) in enumerate(sorted(result.counts.get("by_split", {}).items()))]


@task(name="export-dataset", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def export_dataset_task(store_root: str, out: str | None, config: ExportConfig) -> ExportResult:
    """``export_dataset`` as a Prefect task: step progress over the inputs, the splits as a table artifact."""
    result = export_dataset(store_root, out, config, progress=StepProgress(f"export {config.name}", headline=""))
    publish_rows(export_rows(result), key="exported-dataset",
                 description=f"Dataset {result.dataset_uri}: {result.written} new scenario(s), "
                             f"{len(result.left_out)} left out")
    return result
