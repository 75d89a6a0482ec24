"""Writing small Parquet datasets in the ``parquet_tables`` layout for the tests."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from simsplat_core.export.parquet_tables import TABLE_SCHEMAS, scenario_tables, shard_path
from simsplat_core.export.record import ExportScenario


def write_dataset(root: Path, shards: Mapping[tuple[str, str], Sequence[ExportScenario]]) -> Path:
    """Write ``{(split, shard): scenarios}`` under ``root`` (the ``<dataset>/parquet`` folder); returns ``root``."""
    for (split, shard), scenarios in shards.items():
        per_table = [scenario_tables(s, split) for s in scenarios]
        for table in TABLE_SCHEMAS:
            path = root / shard_path(table, split, shard)
            path.parent.mkdir(parents=True, exist_ok=True)
            pq.write_table(pa.concat_tables([tables[table] for tables in per_table]), path)
    return root
