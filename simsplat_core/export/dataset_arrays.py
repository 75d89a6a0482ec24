"""A Parquet dataset's scenarios as dense numpy arrays: the agents' ``[A, T]`` grids and the map densified.

``load_scenario_arrays`` reads the ``scenarios``, ``agents``, ``map_features`` and ``signals`` tables of one split
(``parquet_tables`` layout) once with pyarrow and groups them per scenario, vectorised over rows; the rows need not
be sorted, and an ``agents`` table without the invalid rows (a filtered copy) still fills the grid. Units and
frames are the tables' (metres and radians in the scenario's world frame, m/s).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from simsplat_core.export.parquet_tables import MissingTableError, read_dataset_table
from simsplat_core.export.record import (
    AGENT_TYPES,
    MAP_FEATURE_KINDS,
    POLYGON_KINDS,
    SIGNAL_STATES,
    TRACK_SOURCES,
)

logger = logging.getLogger(__name__)

#: The ``agents`` columns of ``ScenarioArrays.states[..., k]``, in ``record.STATE_COLUMNS`` order.
STATE_TABLE_COLUMNS: tuple[str, ...] = (
    "x", "y", "z", "length", "width", "height", "heading", "velocity_x", "velocity_y",
)
#: Spacing (metres) of the densified map points.
DENSIFY_STEP_M = 1.0


@dataclass(frozen=True, eq=False)
class ScenarioArrays:
    """One scenario of a dataset. ``A`` tracks (sorted by id), ``T`` steps, ``F`` map features, ``Q`` map points.

    Attributes:
        scenario_id: the scenario's id.
        split: its split.
        current_time_index: the last observed step.
        edited: the scenario comes from an edit (an ``edit_id``, or a track not from the log).
        track_ids: ``[A]`` int64.
        agent_types: ``[A]`` int64 index into ``record.AGENT_TYPES``.
        sources: ``[A]`` int64 index into ``record.TRACK_SOURCES``.
        is_sdc, of_interest, to_predict: ``[A]`` bool.
        states: ``[A, T, 9]`` float32 box states (``record.STATE_COLUMNS``); zeros where invalid.
        valid: ``[A, T]`` bool.
        feature_ids: ``[F]`` int64 map feature ids.
        feature_kinds: ``[F]`` int64 index into ``record.MAP_FEATURE_KINDS``.
        map_points: ``[Q, 3]`` float32 every feature's points at most ``DENSIFY_STEP_M`` apart (polygons closed),
            grouped by feature in order.
        map_point_feature: ``[Q]`` int64 the feature (row of ``feature_ids``) of each point, non-decreasing.
        signal_states: ``[T, F]`` int64 index into ``record.SIGNAL_STATES`` of each lane's signal; -1 for none.
    """

    scenario_id: str
    split: str
    current_time_index: int
    edited: bool
    track_ids: np.ndarray
    agent_types: np.ndarray
    sources: np.ndarray
    is_sdc: np.ndarray
    of_interest: np.ndarray
    to_predict: np.ndarray
    states: np.ndarray
    valid: np.ndarray
    feature_ids: np.ndarray
    feature_kinds: np.ndarray
    map_points: np.ndarray
    map_point_feature: np.ndarray
    signal_states: np.ndarray

    @property
    def num_steps(self) -> int:
        return int(self.valid.shape[1])


def _encode(column: pa.ChunkedArray | pa.Array) -> tuple[list[str], np.ndarray]:
    """A string column as its distinct values and ``[N]`` int64 codes into them."""
    array = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
    encoded = pc.dictionary_encode(array)
    return encoded.dictionary.to_pylist(), encoded.indices.to_numpy(zero_copy_only=False).astype(np.int64)


def _codes(column: pa.ChunkedArray | pa.Array, names: tuple[str, ...], what: str) -> np.ndarray:
    """Strings -> their index in ``names``; an unknown value raises naming ``what``."""
    values, codes = _encode(column)
    unknown = sorted(set(values) - set(names))
    if unknown:
        raise ValueError(f"{what}: unknown values {unknown[:5]}; known: {list(names)}")
    return np.array([names.index(v) for v in values], np.int64)[codes]


def _groups(keys: pa.ChunkedArray, order_by: list[np.ndarray]) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Rows grouped by ``keys`` (string column): the distinct keys, the row order (by key, then ``order_by`` in
    turn) and the start of each key's rows in that order (``[K + 1]``)."""
    names, codes = _encode(keys)
    order = np.lexsort([*order_by[::-1], codes])
    bounds = np.searchsorted(codes[order], np.arange(len(names) + 1))
    return names, order, bounds


def densify_polylines(points: np.ndarray, offsets: np.ndarray, closed: np.ndarray, step_m: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Insert points along every segment so that consecutive points are at most ``step_m`` apart.

    Args:
        points: ``[N, 3]`` the features' points, grouped by feature.
        offsets: ``[F + 1]`` feature ``f`` holds ``points[offsets[f]:offsets[f + 1]]`` (at least one point).
        closed: ``[F]`` bool, polygons: the last point connects back to the first.
        step_m: the largest spacing (metres).

    Returns:
        ``[Q, 3]`` the densified points grouped by feature in order, ``[Q]`` int64 the feature of each.
    """
    counts = np.diff(offsets)
    feature_of = np.repeat(np.arange(len(counts)), counts)
    close = np.asarray(closed, bool) & (counts >= 3)
    rows = np.concatenate([np.arange(len(points)), offsets[:-1][close]])
    feature = np.concatenate([feature_of, np.flatnonzero(close)])
    position = np.concatenate([np.arange(len(points)) - offsets[:-1][feature_of], counts[close]])
    order = np.lexsort([position, feature])
    pts, feature = np.asarray(points, np.float64)[rows[order]], feature[order]
    same = feature[1:] == feature[:-1]
    starts, deltas, seg_feature = pts[:-1][same], (pts[1:] - pts[:-1])[same], feature[:-1][same]
    pieces = np.maximum(1, np.ceil(np.linalg.norm(deltas, axis=1) / step_m)).astype(np.int64)
    seg = np.repeat(np.arange(len(starts)), pieces)
    frac = (np.arange(len(seg)) - np.repeat(np.cumsum(pieces) - pieces, pieces)) / np.repeat(pieces, pieces)
    last = np.flatnonzero(np.append(feature[1:] != feature[:-1], True))
    dense = np.concatenate([starts[seg] + frac[:, None] * deltas[seg], pts[last]])
    dense_feature = np.concatenate([seg_feature[seg], feature[last]])
    keep = np.argsort(dense_feature, kind="stable")
    return dense[keep].astype(np.float32), dense_feature[keep].astype(np.int64)


@dataclass(frozen=True)
class _ScenarioFacts:
    num_steps: int
    current_time_index: int
    edit_id: str


def _scenario_facts(table: pa.Table) -> dict[str, _ScenarioFacts]:
    ids = table.column("scenario_id").to_pylist()
    if len(set(ids)) != len(ids):
        raise ValueError("scenarios table: scenario_id values are not unique")
    return {sid: _ScenarioFacts(int(t), int(c), str(e)) for sid, t, c, e in zip(
        ids, table.column("num_steps").to_pylist(), table.column("current_time_index").to_pylist(),
        table.column("edit_id").to_pylist())}


def _agent_grids(table: pa.Table, facts: dict[str, _ScenarioFacts]) -> dict[str, dict[str, np.ndarray]]:
    """Per scenario: its tracks' columns and dense ``[A, T]`` grids from the ``agents`` rows."""
    track = table.column("track_id").to_numpy().astype(np.int64)
    step = table.column("step").to_numpy().astype(np.int64)
    names, order, bounds = _groups(table.column("scenario_id"), [track, step])
    states = np.stack([table.column(c).to_numpy().astype(np.float32) for c in STATE_TABLE_COLUMNS], axis=1)
    valid = table.column("valid").to_numpy(zero_copy_only=False).astype(bool)
    per_row = {
        "agent_types": _codes(table.column("type"), AGENT_TYPES, "agents table, column 'type'"),
        "sources": _codes(table.column("source"), TRACK_SOURCES, "agents table, column 'source'"),
        **{c: table.column(c).to_numpy(zero_copy_only=False).astype(bool)
           for c in ("is_sdc", "of_interest", "to_predict")},
    }
    grids: dict[str, dict[str, np.ndarray]] = {}
    for k, sid in enumerate(names):
        if sid not in facts:
            raise ValueError(f"agents table: scenario {sid!r} has no row in the scenarios table")
        rows = order[bounds[k]:bounds[k + 1]]
        num_steps = facts[sid].num_steps
        if step[rows].min() < 0 or step[rows].max() >= num_steps:
            raise ValueError(f"agents table: scenario {sid!r} has steps outside 0..{num_steps - 1}")
        ids, first, track_row = np.unique(track[rows], return_index=True, return_inverse=True)
        grid = np.zeros((len(ids), num_steps, len(STATE_TABLE_COLUMNS)), np.float32)
        mask = np.zeros((len(ids), num_steps), bool)
        grid[track_row, step[rows]] = states[rows]
        mask[track_row, step[rows]] = valid[rows]
        grid[~mask] = 0.0
        group = {name: values[rows[first]] for name, values in per_row.items()}
        grids[sid] = {"track_ids": ids, "states": grid, "valid": mask, **group}
    return grids


def _map_arrays(table: pa.Table) -> dict[str, dict[str, np.ndarray]]:
    """Per scenario: feature ids and kinds and the densified points (``ScenarioArrays`` fields)."""
    if table.num_rows == 0:
        return {}
    fid = table.column("feature_id").to_numpy().astype(np.int64)
    names, order, bounds = _groups(table.column("scenario_id"), [fid])
    points_col = table.column("points").combine_chunks()
    offsets = points_col.offsets.to_numpy().astype(np.int64)
    xyz = points_col.flatten().flatten().to_numpy(zero_copy_only=False).reshape(-1, 3)
    kinds = _codes(table.column("kind"), MAP_FEATURE_KINDS, "map_features table, column 'kind'")
    polygon = np.isin(kinds, [MAP_FEATURE_KINDS.index(k) for k in POLYGON_KINDS])
    out: dict[str, dict[str, np.ndarray]] = {}
    for k, sid in enumerate(names):
        rows = order[bounds[k]:bounds[k + 1]]
        counts = offsets[rows + 1] - offsets[rows]
        if np.any(counts == 0):
            raise ValueError(f"map_features table: scenario {sid!r} has a feature without points")
        local_offsets = np.concatenate([[0], np.cumsum(counts)])
        gather = np.arange(local_offsets[-1]) + np.repeat(offsets[rows] - local_offsets[:-1], counts)
        dense, feature = densify_polylines(xyz[gather], local_offsets, polygon[rows], DENSIFY_STEP_M)
        out[sid] = {"feature_ids": fid[rows], "feature_kinds": kinds[rows], "map_points": dense,
                    "map_point_feature": feature}
    return out


def _signal_grids(table: pa.Table, facts: dict[str, _ScenarioFacts], maps: dict[str, dict[str, np.ndarray]]
                  ) -> dict[str, np.ndarray]:
    """Per scenario: ``[T, F]`` signal state indices (-1: none); lanes not among the features are dropped."""
    if table.num_rows == 0:
        return {}
    step = table.column("step").to_numpy().astype(np.int64)
    lane = table.column("lane_id").to_numpy().astype(np.int64)
    states = _codes(table.column("state"), SIGNAL_STATES, "signals table, column 'state'")
    names, order, bounds = _groups(table.column("scenario_id"), [step, lane])
    out: dict[str, np.ndarray] = {}
    for k, sid in enumerate(names):
        if sid not in facts:
            raise ValueError(f"signals table: scenario {sid!r} has no row in the scenarios table")
        rows = order[bounds[k]:bounds[k + 1]]
        feature_ids = maps.get(sid, {}).get("feature_ids", np.zeros(0, np.int64))
        grid = np.full((facts[sid].num_steps, len(feature_ids)), -1, np.int64)
        column = {int(f): c for c, f in enumerate(feature_ids)}
        cols = np.array([column.get(int(lane_id), -1) for lane_id in lane[rows]], np.int64)
        known = (cols >= 0) & (step[rows] >= 0) & (step[rows] < grid.shape[0])
        grid[step[rows][known], cols[known]] = states[rows][known]
        out[sid] = grid
    return out


def load_scenario_arrays(root: str | Path, split: str | None = "train") -> tuple[ScenarioArrays, ...]:
    """Every scenario of ``split`` (``None``: all splits) of the dataset at ``root`` (``<dataset>/parquet``),
    sorted by scenario id. Scenarios without agent rows are skipped."""
    scenarios = read_dataset_table(root, "scenarios", split)
    facts = _scenario_facts(scenarios)
    splits = dict(zip(scenarios.column("scenario_id").to_pylist(), scenarios.column("split").to_pylist()))
    grids = _agent_grids(read_dataset_table(root, "agents", split), facts)
    maps = _map_arrays(_optional_table(root, "map_features", split))
    signals = _signal_grids(_optional_table(root, "signals", split), facts, maps)
    empty_map: dict[str, np.ndarray] = {"feature_ids": np.zeros(0, np.int64), "feature_kinds": np.zeros(0, np.int64),
                                        "map_points": np.zeros((0, 3), np.float32),
                                        "map_point_feature": np.zeros(0, np.int64)}
    out = []
    for sid in sorted(grids):
        grid, fact, feature_map = grids[sid], facts[sid], maps.get(sid, empty_map)
        no_signals = np.full((fact.num_steps, len(feature_map["feature_ids"])), -1, np.int64)
        edited = bool(fact.edit_id) or bool(np.any(grid["sources"] != TRACK_SOURCES.index("log")))
        out.append(ScenarioArrays(scenario_id=sid, split=str(splits[sid]), current_time_index=fact.current_time_index,
                                  edited=edited, **grid, **feature_map, signal_states=signals.get(sid, no_signals)))
    logger.info("loaded %d scenarios of split %s from %s", len(out), split or "(all)", root)
    return tuple(out)


def _optional_table(root: str | Path, table: str, split: str | None) -> pa.Table:
    """A table that a dataset without maps or signals may lack entirely: empty when its folder or split is."""
    try:
        return read_dataset_table(root, table, split)
    except MissingTableError:
        return pa.table({})
