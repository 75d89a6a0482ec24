"""Every declared evaluation table (``TableSpec``), by name: what ``simsplat eval all``, the run-table reader and
Prefect table artifacts list and render.

    for spec in EVAL_TABLES.values(): print(spec.name, spec.title)
    spec = table_spec("motion")               # KeyError naming the known tables
"""

from __future__ import annotations

from collections.abc import Mapping

import pyarrow as pa

from simsplat_core.eval.editing.outcomes import EDITING_SPECS
from simsplat_core.eval.grounding.tables import ABLATION_SPEC, GROUNDING_SPEC
from simsplat_core.eval.grounding.tables import OUTCOMES_SPEC as GROUNDING_OUTCOMES_SPEC
from simsplat_core.eval.mining import MINING_SPECS
from simsplat_core.eval.refinement.diagnosis import STALLS_SPEC as MOTION_STALLS_SPEC
from simsplat_core.eval.refinement.table import MOTION_SPEC
from simsplat_core.eval.refinement.table import OUTCOMES_SPEC as MOTION_OUTCOMES_SPEC
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from simsplat_core.eval.store_tables import RECONSTRUCTION_SPEC, THROUGHPUT_SPEC
from simsplat_core.eval.table_spec import TableSpec

#: Every evaluation table, by name, in the order summaries list them.
EVAL_TABLES: dict[str, TableSpec] = {spec.name: spec for spec in (
    RECONSTRUCTION_SPEC, THROUGHPUT_SPEC, GROUNDING_SPEC, ABLATION_SPEC, GROUNDING_OUTCOMES_SPEC, *EDITING_SPECS,
    MOTION_SPEC, MOTION_OUTCOMES_SPEC, MOTION_STALLS_SPEC, *MINING_SPECS, SEARCH_SPEC)}


def table_spec(name: str) -> TableSpec:
    """The declaration of table ``name``.

    Raises:
        KeyError: no evaluation table of that name (naming the known ones).
    """
    if name not in EVAL_TABLES:
        raise KeyError(f"no evaluation table {name!r}; known: {list(EVAL_TABLES)}")
    return EVAL_TABLES[name]


__all__ = ["EVAL_TABLES", "summary_markdown", "table_spec"]


def summary_markdown(run_id: str, tables: Mapping[str, pa.Table], skipped: Mapping[str, str],
                     seconds: Mapping[str, float]) -> str:
    """The run's ``summary.md``: each table under its title (what a row is, its Markdown), then the skipped
    evaluations with their reasons."""
    parts = [f"# Evaluation {run_id}\n", "| table | rows | title |\n|:---|---:|:---|\n" + "".join(
        f"| {name} | {table.num_rows} | {table_spec(name).title} |\n" for name, table in tables.items())]
    for name, table in tables.items():
        spec = table_spec(name)
        parts.append(f"## {spec.title} (`{name}`)\n\nOne row per {spec.row}.\n\n{spec.render_markdown(table)}")
    if skipped:
        parts.append("## Skipped\n\n" + "".join(f"- {group}: {why}\n" for group, why in skipped.items()))
    parts.append("## Wall time\n\n" + "".join(f"- {group}: {s:.1f} s\n" for group, s in seconds.items()))
    return "\n".join(parts)
