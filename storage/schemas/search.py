"""Schema of the ``search_frames`` cache table: the per-frame search facts of one log (one row per object and
frame, objects in the order of ``simsplat_core.search.frames.log_frames``). Floats are float64 so a cached log
answers exactly as one computed afresh."""

from __future__ import annotations

import pyarrow as pa

from storage.schemas.base import make_schema


def search_frames_schema(contexts: int) -> pa.Schema:
    """The schema with ``contexts`` map-context flags per row (``contexts`` column, ``FixedSizeList<bool>``)."""
    return make_schema(
        "search_frames",
        1,
        [
            ("object_id", pa.string()),
            ("category", pa.string()),
            ("kind", pa.string()),
            ("frame_s", pa.float64()),
            ("present", pa.bool_()),
            ("motion", pa.string()),
            ("sector", pa.string()),
            ("contexts", pa.list_(pa.bool_(), contexts)),
            ("x", pa.float64()),
            ("y", pa.float64()),
            ("x_ego", pa.float64()),
            ("y_ego", pa.float64()),
            ("heading", pa.float64()),
            ("speed", pa.float64()),
            ("lane_along", pa.float64()),
            ("lane_offset", pa.float64()),
        ],
        contexts=contexts,
    )
