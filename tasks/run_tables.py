"""The declared evaluation tables written in a run directory, read back for printing (the CLI's generic printer):

    for spec, table in load_run_tables(out_root):          # registry order; per-item tables left out
        header, rows = spec.rows_for_console(table)
"""

from __future__ import annotations

import pyarrow as pa

from simsplat_core.eval.table_registry import EVAL_TABLES
from simsplat_core.eval.table_spec import TableSpec
from storage import ArtifactStore
from storage.runs import list_run_tables, read_run_table


def load_run_tables(out_root: str, out_relpath: str = "", *, detail: bool = False) -> list[tuple[TableSpec, pa.Table]]:
    """Every declared table under ``<out_root>/<out_relpath>/tables``, validated, in the registry's order; tables
    marked ``detail`` (one row per prompt, query or case) only when ``detail``. Undeclared files are left out.

    Raises:
        SchemaError: a table does not match its declaration (naming the file and the column).
    """
    store = ArtifactStore(out_root)
    present = set(list_run_tables(store, out_relpath))
    return [(spec, read_run_table(store, out_relpath, spec)) for name, spec in EVAL_TABLES.items()
            if name in present and (detail or not spec.detail)]


__all__ = ["load_run_tables"]
