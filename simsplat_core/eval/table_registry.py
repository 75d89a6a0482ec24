"""Every declared evaluation table (``TableSpec``), by name: what ``simsplat eval all``, the run-table reader and
Prefect table artifacts list and render.

    for spec in EVAL_TABLES.values(): print(spec.name, spec.title)
    spec = table_spec("motion")               # KeyError naming the known tables
"""

from __future__ import annotations

from simsplat_core.eval.editing.outcomes import EDITING_SPECS
from simsplat_core.eval.grounding.tables import ABLATION_SPEC, GROUNDING_SPEC
from simsplat_core.eval.grounding.tables import OUTCOMES_SPEC as GROUNDING_OUTCOMES_SPEC
from simsplat_core.eval.mining import MINING_SPECS
from simsplat_core.eval.refinement.table import MOTION_SPEC
from simsplat_core.eval.refinement.table import OUTCOMES_SPEC as MOTION_OUTCOMES_SPEC
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from simsplat_core.eval.store_tables import RECONSTRUCTION_SPEC, THROUGHPUT_SPEC
from simsplat_core.eval.table_spec import TableSpec

#: Every evaluation table, by name, in the order summaries list them.
EVAL_TABLES: dict[str, TableSpec] = {spec.name: spec for spec in (
    RECONSTRUCTION_SPEC, THROUGHPUT_SPEC, GROUNDING_SPEC, ABLATION_SPEC, GROUNDING_OUTCOMES_SPEC, *EDITING_SPECS,
    MOTION_SPEC, MOTION_OUTCOMES_SPEC, *MINING_SPECS, SEARCH_SPEC)}


def table_spec(name: str) -> TableSpec:
    """The declaration of table ``name``.

    Raises:
        KeyError: no evaluation table of that name (naming the known ones).
    """
    if name not in EVAL_TABLES:
        raise KeyError(f"no evaluation table {name!r}; known: {list(EVAL_TABLES)}")
    return EVAL_TABLES[name]


__all__ = ["EVAL_TABLES", "table_spec"]
