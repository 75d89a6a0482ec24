"""Schema of the ``metrics`` table (one row per measurement of a run's stage)."""

from __future__ import annotations

import pyarrow as pa

from storage.schemas.base import make_schema

METRICS_SCHEMA = make_schema(
    "metrics",
    1,
    [
        ("run_id", pa.string()),
        ("seq_id", pa.string()),
        ("stage", pa.string()),
        ("name", pa.string()),
        ("value", pa.float64()),
        ("unit", pa.string()),
    ],
)
