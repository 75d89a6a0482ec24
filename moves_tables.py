"""Rewrite imports from module paths the table-declaration refactor moved, in place.

    python moves_tables.py DIR [DIR ...]

Rewrites ``from X import a, b`` (one line or parenthesised) where a name moved to another module (one import line
per new module), plain ``import X`` / dotted mentions of moved modules in .py, .md and .toml files:

* ``storage.schemas`` (one module) -> the package ``storage.schemas.{base,logs,scenes,language,edits,runs,registry,
  validation}``; ``storage.schemas.TableSpec`` -> ``storage.schemas.registry.StoredTable``;
* ``simsplat_core.eval.tables`` -> ``simsplat_core.eval.grounding.tables``, its ``markdown`` ->
  ``simsplat_core.eval.table_spec.markdown``.

Names that were removed (the per-table schema functions of ``storage.schemas``, ``grounding_markdown``,
``motion_markdown``, ``outcomes_markdown``) are reported, not rewritten: use the table's ``TableSpec``.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

_SCHEMAS = {
    "storage.schemas.base": ("SCHEMA_NAME_KEY", "SCHEMA_VERSION_KEY", "vec", "metadata_strings", "schema_name",
                             "schema_version", "vectors_to_arrow", "arrow_to_vectors", "make_schema"),
    "storage.schemas.logs": ("FRAMES_SCHEMA", "EGO_POSES_SCHEMA", "TRACKS_SCHEMA", "OBJECTS_SCHEMA",
                             "MAP_FEATURES_SCHEMA"),
    "storage.schemas.scenes": ("gaussians_schema", "nodes_schema", "NODE_POSES_SCHEMA", "DEFORMATIONS_SCHEMA"),
    "storage.schemas.language": ("NODE_LANGUAGE_SCHEMA",),
    "storage.schemas.edits": ("ASSETS_SCHEMA", "EDITS_MINING_COLUMNS", "EDITS_SCHEMA", "TRAJECTORIES_SCHEMA",
                              "EDIT_POSE_TRACKS_SCHEMA"),
    "storage.schemas.runs": ("METRICS_SCHEMA",),
    "storage.schemas.registry": ("StoredTable", "TABLES", "schema_from_metadata"),
    "storage.schemas.validation": ("validate_table", "fill_added_columns", "json_schema"),
}
#: old module -> {name -> new module}
MOVED_NAMES: dict[str, dict[str, str]] = {
    "storage.schemas": {name: module for module, names in _SCHEMAS.items() for name in names},
    "simsplat_core.eval.tables": {
        "markdown": "simsplat_core.eval.table_spec",
        **{n: "simsplat_core.eval.grounding.tables" for n in ("GROUNDING_COLUMNS", "ABLATION_ROWS", "grounding_table",
                                                              "ablation_table")}},
}
RENAMED = {("storage.schemas", "TableSpec"): ("storage.schemas.registry", "StoredTable")}
MOVED_MODULES = {"simsplat_core.eval.tables": "simsplat_core.eval.grounding.tables"}
REMOVED = {"grounding_table_schema", "editing_table_schema", "mining_table_schema", "motion_table_schema",
           "motion_outcomes_schema", "search_table_schema", "GROUNDING_OUTCOMES_SCHEMA", "EDITING_TABLES",
           "MINING_TABLES", "SEARCH_COLUMNS", "grounding_markdown", "motion_markdown", "outcomes_markdown",
           "write_motion_table", "read_motion_table", "read_motion_outcomes", "TABLE_COLUMNS", "MINING_COLUMNS",
           "MINING_BY_CATEGORY_COLUMNS", "MINING_STAGES_COLUMNS", "OUTCOME_MARKDOWN"}

_FROM = re.compile(r"^(?P<indent>[ \t]*)from (?P<module>[\w.]+) import (?P<names>\([^)]*\)|[^\n]*)", re.M)


def _rewrite_from(match: re.Match[str], path: Path) -> str:
    module, indent = match["module"], match["indent"]
    if module not in MOVED_NAMES:
        return match[0]
    raw = match["names"].strip("()")
    names = [n.strip() for n in re.sub(r"#[^\n]*", "", raw).replace("\n", ",").split(",") if n.strip()]
    groups: dict[str, list[str]] = {}
    for item in names:
        name = item.split(" as ")[0].strip()
        alias = item[len(name):]
        if (module, name) in RENAMED:
            new_module, new_name = RENAMED[(module, name)]
            groups.setdefault(new_module, []).append(new_name + alias)
        elif name in MOVED_NAMES[module]:
            groups.setdefault(MOVED_NAMES[module][name], []).append(item)
        else:
            if name in REMOVED:
                print(f"{path}: {module}.{name} was removed (use the table's TableSpec)", file=sys.stderr)
            groups.setdefault(MOVED_MODULES.get(module, module), []).append(item)
    return "\n".join(f"{indent}from {m} import {', '.join(sorted(ns))}" for m, ns in sorted(groups.items()))


def rewrite(text: str, path: Path) -> str:
    if path.suffix == ".py":
        text = _FROM.sub(lambda m: _rewrite_from(m, path), text)
    for old, new in MOVED_MODULES.items():
        text = re.sub(rf"\b{re.escape(old)}\b", new, text)
    return text


def main(paths: list[str]) -> None:
    for root in paths:
        for path in Path(root).rglob("*"):
            if path.suffix not in (".py", ".md", ".toml") or ".git" in path.parts or path.name == "moves_tables.py":
                continue
            text = path.read_text(encoding="utf-8")
            new = rewrite(text, path)
            if new != text:
                path.write_text(new, encoding="utf-8")
                print(f"rewrote {path}")


if __name__ == "__main__":
    main(sys.argv[1:])
