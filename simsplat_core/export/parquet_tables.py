"""The Parquet dataset of the project's own: table schemas, one scenario's rows, and reading a dataset back.

Any Parquet reader opens it without the project's code (DuckDB, Polars, ``pyarrow.dataset``); the
``torch_dataset`` module builds agent-centric training samples from it.

Layout (hive partitions by split, so a reader sees every split at once with a ``split`` column)::

    <dataset>/parquet/<table>/split=<split>/part-<shard>.parquet

``<table>`` is one of :data:`TABLE_SCHEMAS` (``scenarios``, ``agents``, ``map_features``, ``signals``); a shard
holds the rows of whole scenarios (every table of one scenario lands in shards of the same name). For example::

    duckdb:  SELECT split, count(*) FROM read_parquet('ds/parquet/agents/*/*.parquet', hive_partitioning=true)
             GROUP BY split
    polars:  pl.scan_parquet("ds/parquet/agents/", hive_partitioning=True)
    pyarrow: read_dataset_table("ds/parquet", "agents", split="train")

Tables (one row per ...):

- ``scenarios``: scenario. Its facts (sequence, run, edit, prompt, judge's verdicts, what was resampled) come
  from ``ExportScenario.metadata`` under the ``META_*`` keys below (missing: ``""`` for strings, null for the
  numbers and flags), its renders from the :class:`RenderRef` s the caller gives.
- ``agents``: (scenario, track, step): the dense ``[A, T]`` grid of box states with its validity (rows of
  invalid steps hold zeros), in the scenario's world frame (metres, radians counter-clockwise from +x, m/s).
- ``map_features``: map feature, its points a ``list<fixed_size_list<float32, 3>>`` (x, y, z metres).
- ``signals``: (scenario, step, controlled lane): the lane's signal state, its stop point (null when unknown).

Strings are never null; the nullable columns are named in each schema (``attempt``, ``follows_prompt``,
``plausibility``, ``stop_x/y/z``). Every schema carries ``schema_name`` and ``schema_version`` in its metadata.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.dataset as pads
import pyarrow.parquet as pq

from simsplat_core.export.record import (
    HEADING,
    HEIGHT,
    LENGTH,
    VX,
    VY,
    WIDTH,
    ExportScenario,
    X,
    Y,
    Z,
)

SCHEMA_NAME_KEY = "schema_name"
SCHEMA_VERSION_KEY = "schema_version"
#: The hive partition column of every table.
PARTITION_COLUMN = "split"

# ----------------------------------------------------------------------------- metadata keys
#: ``ExportScenario.metadata`` keys the ``scenarios`` table reads (values are strings).
META_SEQ_ID = "seq_id"
META_LOG_SOURCE = "log_source"  # the log source's registry name ("waymo_open_motion", "synthetic", ...)
META_RUN_ID = "run_id"
META_EDIT_ID = "edit_id"  # "" for an unedited log window
META_ATTEMPT = "attempt"  # integer
META_PROMPT = "prompt"
META_COMMANDS_JSON = "commands_json"  # the edit's validated commands as JSON
META_CATEGORY = "category"  # the edit category
META_MINING_STATUS = "mining_status"  # "accepted" | "rejected" | ...
META_FOLLOWS_PROMPT = "follows_prompt"  # "true" | "false"
META_PLAUSIBILITY = "plausibility"  # integer
META_VALIDATION_JSON = "validation_json"  # the edit's validation report as JSON
META_NOTES = "notes"  # what the export resampled or padded
#: Keys read into string columns of the same name.
META_STRING_KEYS: tuple[str, ...] = (
    META_SEQ_ID, META_LOG_SOURCE, META_RUN_ID, META_EDIT_ID, META_PROMPT, META_COMMANDS_JSON, META_CATEGORY,
    META_MINING_STATUS, META_VALIDATION_JSON, META_NOTES,
)
_TRUE, _FALSE = frozenset({"true", "1", "yes"}), frozenset({"false", "0", "no"})


class MissingTableError(ValueError):
    """A dataset has no folder for a table, or no files of the asked split in it."""


@dataclass(frozen=True)
class RenderRef:
    """One rendered view of a scenario.

    Attributes:
        camera: the camera name.
        frame: the frame index rendered.
        exr_path: the EXR file, as the caller wants it stored (relative to the dataset, a store URI ...); ``""``
            when none.
        png_path: the PNG preview, likewise.
    """

    camera: str
    frame: int
    exr_path: str = ""
    png_path: str = ""


def _schema(name: str, version: int, fields: list[tuple[str, pa.DataType]], nullable: tuple[str, ...] = ()
            ) -> pa.Schema:
    metadata = {SCHEMA_NAME_KEY: name, SCHEMA_VERSION_KEY: str(version)}
    return pa.schema([pa.field(n, t, nullable=n in nullable) for n, t in fields], metadata=metadata)


_IDS = pa.list_(pa.int64())
_RENDER = pa.struct([("camera", pa.string()), ("frame", pa.int32()), ("exr_path", pa.string()),
                     ("png_path", pa.string())])
#: ``[P]`` points of a map feature, each (x, y, z) metres.
POINTS_TYPE = pa.list_(pa.list_(pa.float32(), 3))

SCENARIOS_SCHEMA = _schema(
    "dataset_scenarios",
    1,
    [
        ("scenario_id", pa.string()),
        ("split", pa.string()),
        ("seq_id", pa.string()),
        ("log_source", pa.string()),
        ("run_id", pa.string()),
        ("edit_id", pa.string()),  # "" for an unedited log window
        ("attempt", pa.int32()),
        ("prompt", pa.string()),
        ("commands_json", pa.string()),
        ("category", pa.string()),
        ("mining_status", pa.string()),
        ("follows_prompt", pa.bool_()),  # the judge's verdicts (null when not judged)
        ("plausibility", pa.int32()),
        ("validation_json", pa.string()),
        ("num_tracks", pa.int32()),
        ("num_steps", pa.int32()),
        ("current_time_index", pa.int32()),
        ("dt_s", pa.float64()),  # median step (seconds); 0 for one step
        ("sdc_track_id", pa.int64()),
        ("objects_of_interest", _IDS),  # track ids
        ("tracks_to_predict", _IDS),  # track ids (not rows)
        ("window_start_s", pa.float64()),  # the first step's time, seconds from the log's first frame
        ("notes", pa.string()),
        ("metadata_json", pa.string()),  # every metadata entry, sorted keys
        ("renders", pa.list_(_RENDER)),
    ],
    nullable=("attempt", "follows_prompt", "plausibility"),
)

AGENTS_SCHEMA = _schema(
    "dataset_agents",
    1,
    [
        ("scenario_id", pa.string()),
        ("track_id", pa.int64()),
        ("object_id", pa.string()),  # the object's id in the stored log or edit ("ego" for the SDC)
        ("type", pa.string()),  # record.AGENT_TYPES
        ("source", pa.string()),  # record.TRACK_SOURCES
        ("is_sdc", pa.bool_()),
        ("of_interest", pa.bool_()),
        ("to_predict", pa.bool_()),
        ("step", pa.int32()),
        ("t_s", pa.float64()),
        ("x", pa.float32()),  # box centre, metres, world frame
        ("y", pa.float32()),
        ("z", pa.float32()),
        ("length", pa.float32()),
        ("width", pa.float32()),
        ("height", pa.float32()),
        ("heading", pa.float32()),  # radians counter-clockwise from world +x
        ("velocity_x", pa.float32()),  # m/s, world frame
        ("velocity_y", pa.float32()),
        ("valid", pa.bool_()),
    ],
)

MAP_FEATURES_SCHEMA = _schema(
    "dataset_map_features",
    1,
    [
        ("scenario_id", pa.string()),
        ("feature_id", pa.int64()),
        ("kind", pa.string()),  # record.MAP_FEATURE_KINDS
        ("type", pa.string()),  # record.MAP_TYPES of its kind; "" when the kind has none
        ("points", POINTS_TYPE),  # polyline, polygon (implicitly closed) or the one point of a stop sign
        ("entry_lanes", _IDS),
        ("exit_lanes", _IDS),
        ("left_neighbors", _IDS),
        ("right_neighbors", _IDS),
        ("controlled_lanes", _IDS),
        ("speed_limit_mph", pa.float32()),  # 0 when unknown
        ("source_id", pa.string()),
    ],
)

SIGNALS_SCHEMA = _schema(
    "dataset_signals",
    1,
    [
        ("scenario_id", pa.string()),
        ("step", pa.int32()),
        ("lane_id", pa.int64()),
        ("state", pa.string()),  # record.SIGNAL_STATES
        ("stop_x", pa.float32()),  # metres, world frame; null when unknown
        ("stop_y", pa.float32()),
        ("stop_z", pa.float32()),
    ],
    nullable=("stop_x", "stop_y", "stop_z"),
)

#: Table name (its folder under ``<dataset>/parquet/``) -> schema.
TABLE_SCHEMAS: dict[str, pa.Schema] = {
    "scenarios": SCENARIOS_SCHEMA,
    "agents": AGENTS_SCHEMA,
    "map_features": MAP_FEATURES_SCHEMA,
    "signals": SIGNALS_SCHEMA,
}


def shard_path(table: str, split: str, shard: str) -> str:
    """The path of one shard file relative to ``<dataset>/parquet`` (module docstring)."""
    if table not in TABLE_SCHEMAS:
        raise ValueError(f"unknown dataset table {table!r}; known: {list(TABLE_SCHEMAS)}")
    for name, value in (("split", split), ("shard", shard)):
        if not value or "/" in value or "=" in value or value.startswith("."):
            raise ValueError(f"{name} {value!r} cannot name a partition folder or file")
    return f"{table}/{PARTITION_COLUMN}={split}/part-{shard}.parquet"


# ----------------------------------------------------------------------------- one scenario's rows
def scenario_tables(s: ExportScenario, split: str, renders: Sequence[RenderRef] = ()) -> dict[str, pa.Table]:
    """The rows of one scenario in every table (:data:`TABLE_SCHEMAS` order), each with its table's schema."""
    return {
        "scenarios": scenarios_table(s, split, renders),
        "agents": agents_table(s),
        "map_features": map_features_table(s),
        "signals": signals_table(s),
    }


def _meta_int(s: ExportScenario, key: str) -> int | None:
    text = s.metadata.get(key, "").strip()
    if not text:
        return None
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"scenario {s.scenario_id!r}: metadata {key!r} must be an integer, got {text!r}") from None


def _meta_bool(s: ExportScenario, key: str) -> bool | None:
    text = s.metadata.get(key, "").strip().lower()
    if not text:
        return None
    if text in _TRUE | _FALSE:
        return text in _TRUE
    raise ValueError(f"scenario {s.scenario_id!r}: metadata {key!r} must be true or false, got {text!r}")


def scenarios_table(s: ExportScenario, split: str, renders: Sequence[RenderRef] = ()) -> pa.Table:
    """The scenario's one ``scenarios`` row (module docstring)."""
    if not split:
        raise ValueError(f"scenario {s.scenario_id!r}: split must not be empty")
    ids = s.track_ids.astype(np.int64)
    steps = np.diff(s.timestamps_s)
    row: dict[str, object] = {key: s.metadata.get(key, "") for key in META_STRING_KEYS}
    row.update(
        scenario_id=s.scenario_id,
        split=split,
        attempt=_meta_int(s, META_ATTEMPT),
        follows_prompt=_meta_bool(s, META_FOLLOWS_PROMPT),
        plausibility=_meta_int(s, META_PLAUSIBILITY),
        num_tracks=s.num_tracks,
        num_steps=s.num_steps,
        current_time_index=s.current_time_index,
        dt_s=float(np.median(steps)) if len(steps) else 0.0,
        sdc_track_id=int(ids[s.sdc_index]),
        objects_of_interest=[int(i) for i in s.objects_of_interest],
        tracks_to_predict=[int(ids[r]) for r in s.tracks_to_predict],
        window_start_s=float(s.timestamps_s[0]),
        metadata_json=json.dumps(dict(s.metadata), sort_keys=True),
        renders=[{"camera": r.camera, "frame": int(r.frame), "exr_path": r.exr_path, "png_path": r.png_path}
                 for r in renders],
    )
    return pa.Table.from_pylist([row], schema=SCENARIOS_SCHEMA)


def agents_table(s: ExportScenario) -> pa.Table:
    """The scenario's ``[A, T]`` grid as ``A * T`` ``agents`` rows, track-major (row ``a * T + t``)."""
    a, t = s.num_tracks, s.num_steps
    ids = s.track_ids.astype(np.int64)
    rows = np.arange(a)
    sources = s.track_sources or ("log",) * a
    objects = s.source_object_ids or ("",) * a
    states = np.asarray(s.states, dtype=np.float32).reshape(a * t, -1)

    def per_track(values: np.ndarray) -> np.ndarray:
        return np.repeat(values, t)

    columns = {
        "scenario_id": pa.array([s.scenario_id] * (a * t), pa.string()),
        "track_id": per_track(ids),
        "object_id": pa.array(per_track(np.asarray(objects, dtype=object)), pa.string()),
        "type": pa.array(per_track(np.asarray(s.agent_types, dtype=object)), pa.string()),
        "source": pa.array(per_track(np.asarray(sources, dtype=object)), pa.string()),
        "is_sdc": per_track(rows == s.sdc_index),
        "of_interest": per_track(np.isin(ids, np.asarray(s.objects_of_interest, dtype=np.int64))),
        "to_predict": per_track(np.isin(rows, np.asarray(s.tracks_to_predict, dtype=np.int64))),
        "step": np.tile(np.arange(t, dtype=np.int32), a),
        "t_s": np.tile(np.asarray(s.timestamps_s, dtype=np.float64), a),
    }
    for name, k in (("x", X), ("y", Y), ("z", Z), ("length", LENGTH), ("width", WIDTH), ("height", HEIGHT),
                    ("heading", HEADING), ("velocity_x", VX), ("velocity_y", VY)):
        columns[name] = states[:, k]
    columns["valid"] = np.asarray(s.valid, dtype=bool).reshape(-1)
    return pa.Table.from_pydict(columns, schema=AGENTS_SCHEMA)


def _id_lists(values: Sequence[tuple[int, ...]]) -> pa.Array:
    return pa.array([list(v) for v in values], _IDS)


def map_features_table(s: ExportScenario) -> pa.Table:
    """The scenario's ``map_features`` rows, one per feature in ``s.map_features`` order."""
    features = s.map_features
    counts = np.array([len(f.points) for f in features], dtype=np.int32)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    flat = (np.concatenate([np.asarray(f.points, np.float32) for f in features]).reshape(-1)
            if features else np.zeros(0, np.float32))
    xyz = pa.FixedSizeListArray.from_arrays(pa.array(flat, pa.float32()), 3)
    columns = {
        "scenario_id": pa.array([s.scenario_id] * len(features), pa.string()),
        "feature_id": pa.array([f.feature_id for f in features], pa.int64()),
        "kind": pa.array([f.kind for f in features], pa.string()),
        "type": pa.array([f.type for f in features], pa.string()),
        "points": pa.ListArray.from_arrays(pa.array(offsets), xyz, type=POINTS_TYPE),
        "entry_lanes": _id_lists([f.entry_lanes for f in features]),
        "exit_lanes": _id_lists([f.exit_lanes for f in features]),
        "left_neighbors": _id_lists([f.left_neighbors for f in features]),
        "right_neighbors": _id_lists([f.right_neighbors for f in features]),
        "controlled_lanes": _id_lists([f.controlled_lanes for f in features]),
        "speed_limit_mph": pa.array([f.speed_limit_mph for f in features], pa.float32()),
        "source_id": pa.array([f.source_id for f in features], pa.string()),
    }
    return pa.Table.from_pydict(columns, schema=MAP_FEATURES_SCHEMA)


def signals_table(s: ExportScenario) -> pa.Table:
    """The scenario's ``signals`` rows, step-major in ``s.signals`` order."""
    entries = [(step, sig) for step, states in enumerate(s.signals) for sig in states]
    stops = [None if sig.stop_point is None else np.asarray(sig.stop_point, np.float64) for _, sig in entries]
    columns: dict[str, pa.Array] = {
        "scenario_id": pa.array([s.scenario_id] * len(entries), pa.string()),
        "step": pa.array([step for step, _ in entries], pa.int32()),
        "lane_id": pa.array([sig.lane_id for _, sig in entries], pa.int64()),
        "state": pa.array([sig.state for _, sig in entries], pa.string()),
    }
    for k, name in enumerate(("stop_x", "stop_y", "stop_z")):
        columns[name] = pa.array([None if p is None else float(p[k]) for p in stops], pa.float32())
    return pa.Table.from_pydict(columns, schema=SIGNALS_SCHEMA)


# ----------------------------------------------------------------------------- reading a dataset
def read_dataset_table(root: str | Path, table: str, split: str | None = None,
                       columns: Sequence[str] | None = None) -> pa.Table:
    """One table of every split (or of ``split``) of a dataset, with the ``split`` partition column.

    Args:
        root: the ``<dataset>/parquet`` folder.
        table: one of :data:`TABLE_SCHEMAS`.
        split: the split to read; ``None`` reads all.
        columns: the columns to read (default all, ``split`` last).

    Returns:
        the rows with the table's schema (and metadata) plus ``split`` (string); files of an older schema version
        read their missing nullable columns as nulls.

    Raises:
        MissingTableError: no folder for ``table``, or no files of ``split`` in it.
        ValueError: an unknown table, or a file whose ``schema_name`` is not the table's (or of a newer version).
    """
    if table not in TABLE_SCHEMAS:
        raise ValueError(f"unknown dataset table {table!r}; known: {list(TABLE_SCHEMAS)}")
    folder = Path(root) / table
    if not folder.is_dir():
        raise MissingTableError(f"{folder}: no such dataset table folder")
    declared = TABLE_SCHEMAS[table]
    schema = declared if PARTITION_COLUMN in declared.names else declared.append(
        pa.field(PARTITION_COLUMN, pa.string()))
    partitioning = pads.partitioning(pa.schema([(PARTITION_COLUMN, pa.string())]), flavor="hive")
    dataset = pads.dataset(str(folder), schema=schema, format="parquet", partitioning=partitioning)
    files = sorted(Path(f) for f in dataset.files)
    if split is not None:
        files = [f for f in files if f.parent.name == f"{PARTITION_COLUMN}={split}"]
    if not files:
        raise MissingTableError(f"{folder}: no files" + (f" for split {split!r}" if split is not None else ""))
    _check_schema_names(files, table, declared)
    chosen = pads.dataset([str(f) for f in files], schema=schema, format="parquet", partitioning=partitioning,
                          partition_base_dir=str(folder))
    result = chosen.to_table(columns=list(columns) if columns is not None else None)
    return result.replace_schema_metadata(declared.metadata)


def _check_schema_names(files: Sequence[Path], table: str, declared: pa.Schema) -> None:
    want = declared.metadata[SCHEMA_NAME_KEY.encode()]
    newest = int(declared.metadata[SCHEMA_VERSION_KEY.encode()])
    for path in files:
        meta = pq.read_schema(path).metadata or {}
        name = meta.get(SCHEMA_NAME_KEY.encode())
        if name != want:
            raise ValueError(f"{path}: schema_name {name!r} is not the {table} table's {want.decode()!r}")
        version = int(meta.get(SCHEMA_VERSION_KEY.encode(), b"0"))
        if version > newest:
            raise ValueError(f"{path}: schema_version {version} is newer than the supported {newest}")
