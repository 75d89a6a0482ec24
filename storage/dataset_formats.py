"""Writing scenarios into a dataset folder, one writer per export format (layout in ``storage.datasets``).

Each writer takes the new scenarios of one split and increment and writes them as new shards, never touching a
shard of an earlier increment; shard names carry the increment and a counter (``part-<increment>-<k>``), so a
killed export's leftovers are replaced by the retry of the same increment. The formats themselves (messages,
dicts, table schemas) are ``simsplat_core.export``'s; this module only names the files and writes them.
"""

from __future__ import annotations

import pickle
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import pyarrow as pa

from simsplat_core.export import parquet_tables, scenarionet, womd
from simsplat_core.export.record import ExportScenario
from storage.datasets import DatasetFolder, ShardRecord

#: The export formats, in the order they are written.
FORMATS: tuple[str, ...] = ("womd", "scenarionet", "parquet")
#: (camera, frame, EXR URI, PNG preview URI) of one scenario's renders.
RenderRefs = Sequence[tuple[str, int, str, str]]


def _chunks(items: Sequence[ExportScenario], size: int) -> Iterator[tuple[int, Sequence[ExportScenario]]]:
    for k, start in enumerate(range(0, len(items), size)):
        yield k, items[start:start + size]


def shard_name(increment: int, k: int) -> str:
    return f"{increment:05d}-{k:04d}"


def _write_womd(folder: DatasetFolder, split: str, increment: int, scenarios: Sequence[ExportScenario],
                shard_size: int, refs: Mapping[str, RenderRefs]) -> list[ShardRecord]:
    return [folder.write_shard(f"womd/{split}/part-{shard_name(increment, k)}.tfrecord", womd.encode_shard(chunk),
                               fmt="womd", split=split, scenarios=len(chunk))
            for k, chunk in _chunks(scenarios, shard_size)]


def _write_parquet(folder: DatasetFolder, split: str, increment: int, scenarios: Sequence[ExportScenario],
                   shard_size: int, refs: Mapping[str, RenderRefs]) -> list[ShardRecord]:
    out = []
    for k, chunk in _chunks(scenarios, shard_size):
        parts: dict[str, list[pa.Table]] = {name: [] for name in parquet_tables.TABLE_SCHEMAS}
        for s in chunk:
            renders = [parquet_tables.RenderRef(*ref) for ref in refs.get(s.scenario_id, ())]
            for name, table in parquet_tables.scenario_tables(s, split, renders).items():
                parts[name].append(table)
        for name, schema in parquet_tables.TABLE_SCHEMAS.items():
            table = pa.concat_tables(parts[name]) if parts[name] else schema.empty_table()
            rel = "parquet/" + parquet_tables.shard_path(name, split, shard_name(increment, k))
            out.append(folder.write_table_shard(rel, table, schema, split=split, scenarios=len(chunk)))
    return out


def _write_scenarionet(folder: DatasetFolder, split: str, increment: int, scenarios: Sequence[ExportScenario],
                       shard_size: int, refs: Mapping[str, RenderRefs]) -> list[ShardRecord]:
    """One pickle per scenario in ``scenarionet/<split>/part-<increment>/`` with that part's summary and mapping,
    then the split's summary and mapping over every part (ScenarioNet's layout for combined datasets)."""
    part = f"part-{increment:05d}"
    base = f"scenarionet/{split}"
    out, descriptions = [], {}
    for s in scenarios:
        description = scenarionet.scenario_description(s)
        name = scenarionet.scenario_file_name(s.scenario_id)
        out.append(folder.write_shard(f"{base}/{part}/{name}", scenarionet.to_pickle(description),
                                      fmt="scenarionet", split=split, scenarios=1))
        descriptions[name] = description
    summary = scenarionet.dataset_summary(descriptions)
    folder.write_index(f"{base}/{part}/{scenarionet.SUMMARY_FILE_NAME}", scenarionet.to_pickle(summary))
    folder.write_index(f"{base}/{part}/{scenarionet.MAPPING_FILE_NAME}",
                       scenarionet.to_pickle(scenarionet.dataset_mapping(summary)))
    top_summary = _read_pickle(folder, f"{base}/{scenarionet.SUMMARY_FILE_NAME}")
    top_mapping = _read_pickle(folder, f"{base}/{scenarionet.MAPPING_FILE_NAME}")
    top_summary.update(summary)
    top_mapping.update(scenarionet.dataset_mapping(summary, part))
    folder.write_index(f"{base}/{scenarionet.SUMMARY_FILE_NAME}", scenarionet.to_pickle(top_summary))
    folder.write_index(f"{base}/{scenarionet.MAPPING_FILE_NAME}", scenarionet.to_pickle(top_mapping))
    return out


def _read_pickle(folder: DatasetFolder, relpath: str) -> dict[str, Any]:
    data = folder.read_index(relpath)
    if data is None:
        return {}
    value = pickle.loads(data)  # noqa: S301 -- an index file this module wrote into the dataset
    if not isinstance(value, dict):
        raise ValueError(f"{folder.uri(relpath)}: not a ScenarioNet index (a dict)")
    return value


_WRITERS: dict[str, Callable[..., list[ShardRecord]]] = {
    "womd": _write_womd, "scenarionet": _write_scenarionet, "parquet": _write_parquet,
}


def write_format(folder: DatasetFolder, fmt: str, split: str, increment: int, scenarios: Sequence[ExportScenario],
                 shard_size: int, refs: Mapping[str, RenderRefs]) -> list[ShardRecord]:
    """Write ``scenarios`` of ``split`` as increment ``increment`` in format ``fmt``; returns the shards."""
    if fmt not in _WRITERS:
        raise ValueError(f"unknown export format {fmt!r}; known: {list(FORMATS)}")
    return _WRITERS[fmt](folder, split, increment, scenarios, shard_size, refs)


def format_versions(formats: Sequence[str]) -> dict[str, Any]:
    """The schema version of each format (the manifest's ``schema_versions``)."""
    versions: dict[str, Any] = {
        "womd": womd.FORMAT_VERSION,
        "scenarionet": scenarionet.SCENARIO_VERSION,
        "parquet": {name: schema.metadata[b"schema_version"].decode() for name, schema
                    in parquet_tables.TABLE_SCHEMAS.items()},
    }
    return {f: versions[f] for f in formats}
