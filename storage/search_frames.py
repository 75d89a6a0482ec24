"""The per-log search facts (``simsplat_core.search.frames.log_frames``) cached in the store, one file per log:
``cache/search_frames/<seq_id>.parquet`` (``storage.keyed_tables``), so search preparation over a growing store
derives facts only for logs it has not seen (or whose content or code changed)."""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from simsplat_core.search.frames import CONTEXTS, ObjectFrames
from storage.keyed_tables import KeyedTables
from storage.schemas.search import search_frames_schema
from storage.store import ArtifactStore

SEARCH_FRAMES = "search_frames"
_FLOATS = ("heading", "speed", "lane_along", "lane_offset")


def search_frames_cache(store: ArtifactStore) -> KeyedTables:
    """The store's cache of per-log search facts."""
    return KeyedTables(store, SEARCH_FRAMES, search_frames_schema(len(CONTEXTS)))


def frames_to_table(objects: dict[str, ObjectFrames]) -> pa.Table:
    """``object_id -> ObjectFrames`` (each over ``F`` frames) -> one row per (object, frame), objects in order."""
    items = list(objects.values())
    frames = [len(o.present) for o in items]

    def per_object(values: list[object]) -> list[object]:
        return [v for v, n in zip(values, frames) for _ in range(n)]

    def joined(name: str, dtype: type) -> np.ndarray:
        parts: list[np.ndarray] = [np.asarray(getattr(o, name), dtype=dtype).reshape(len(o.present), -1) for o in items]
        return np.concatenate(parts) if parts else np.zeros((0, 1), dtype)

    xy, xy_ego = joined("xy", np.float64), joined("xy_ego", np.float64)
    flags = joined("contexts", np.bool_).reshape(-1)
    columns: dict[str, pa.Array] = {
        "object_id": pa.array(per_object([o.object_id for o in items]), pa.string()),
        "category": pa.array(per_object([o.category for o in items]), pa.string()),
        "kind": pa.array(per_object([o.kind for o in items]), pa.string()),
        "frame_s": pa.array(per_object([float(o.frame_s) for o in items]), pa.float64()),
        "present": pa.array(joined("present", np.bool_).reshape(-1), pa.bool_()),
        "motion": pa.array([str(v) for o in items for v in o.motion], pa.string()),
        "sector": pa.array([str(v) for o in items for v in o.sector], pa.string()),
        "contexts": pa.FixedSizeListArray.from_arrays(pa.array(flags, pa.bool_()), len(CONTEXTS)),
        "x": pa.array(xy[:, 0] if len(xy) else [], pa.float64()),
        "y": pa.array(xy[:, 1] if len(xy) else [], pa.float64()),
        "x_ego": pa.array(xy_ego[:, 0] if len(xy_ego) else [], pa.float64()),
        "y_ego": pa.array(xy_ego[:, 1] if len(xy_ego) else [], pa.float64()),
    }
    for name in _FLOATS:
        columns[name] = pa.array(joined(name, np.float64).reshape(-1), pa.float64())
    return pa.table(columns)


def table_to_frames(table: pa.Table) -> dict[str, ObjectFrames]:
    """The inverse of :func:`frames_to_table` (float64 facts, ``object`` arrays of names, bool flags)."""
    ids = table.column("object_id").to_pylist()
    cols = {name: table.column(name) for name in table.column_names}
    floats = {n: cols[n].to_numpy() for n in ("x", "y", "x_ego", "y_ego", *_FLOATS)}
    present = cols["present"].to_numpy(zero_copy_only=False).astype(bool)
    motion = np.array(cols["motion"].to_pylist(), dtype=object)
    sector = np.array(cols["sector"].to_pylist(), dtype=object)
    flat = cols["contexts"].combine_chunks().flatten().to_numpy(zero_copy_only=False)
    flags = np.asarray(flat, dtype=bool).reshape(len(ids), len(CONTEXTS))
    categories, kinds, steps = (cols[n].to_pylist() for n in ("category", "kind", "frame_s"))
    out: dict[str, ObjectFrames] = {}
    start = 0
    while start < len(ids):
        stop = start
        while stop < len(ids) and ids[stop] == ids[start]:
            stop += 1
        rows = slice(start, stop)
        out[ids[start]] = ObjectFrames(
            ids[start], categories[start], kinds[start], present[rows].copy(), motion[rows].copy(),
            sector[rows].copy(), flags[rows].copy(),
            np.stack([floats["x"][rows], floats["y"][rows]], axis=1),
            np.stack([floats["x_ego"][rows], floats["y_ego"][rows]], axis=1),
            floats["heading"][rows].copy(), floats["speed"][rows].copy(), floats["lane_along"][rows].copy(),
            floats["lane_offset"][rows].copy(), frame_s=steps[start])
        start = stop
    return out
