"""The data card of an exported dataset: what is in it, how it was made, under which licences, from its manifest."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

#: What each format's files are and which readers take them.
FORMAT_NOTES: dict[str, str] = {
    "womd": "Waymo Open Motion `Scenario` protos in TFRecord shards (`womd/<split>/*.tfrecord`): read by SMART, "
            "MTR-family models, GPUDrive's and ScenarioNet's Waymo converters.",
    "scenarionet": "ScenarioNet scenario descriptions (`scenarionet/<split>/`: one pickle per scenario plus "
                   "`dataset_summary.pkl` and `dataset_mapping.pkl`): read by MetaDrive, UniTraj, ScenarioMax.",
    "parquet": "Parquet tables (`parquet/<table>/split=<split>/*.parquet`: scenarios, agents, map_features, "
               "signals), readable with DuckDB, Polars or pyarrow; `simsplat_core.export.torch_dataset` yields "
               "agent-centric samples from them.",
}


def _table(title: str, counts: Mapping[str, Any]) -> list[str]:
    if not counts:
        return []
    lines = [f"| {title} | scenarios |", "|---|---:|"]
    lines += [f"| {k or '(none)'} | {v} |" for k, v in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))]
    return [*lines, ""]


def datacard_markdown(manifest: Mapping[str, Any]) -> str:
    """The data card (Markdown) of a dataset ``manifest`` (``tasks.export``'s manifest.json)."""
    counts = manifest.get("counts", {})
    layout = manifest.get("layout", {})
    filters = manifest.get("filters", {})
    lines = [
        f"# {manifest.get('name', 'dataset')}",
        "",
        f"{counts.get('scenarios', 0)} driving scenarios exported by simsplat from the artifact store "
        f"`{manifest.get('store', '')}` (code {manifest.get('code_version', 'unknown')}, "
        f"{len(manifest.get('increments', []))} increment(s), last updated {manifest.get('updated', '')}).",
        "",
        "## How it was made",
        "",
        f"- Included: `{filters.get('include', '')}` (runs {filters.get('runs') or 'all'}, categories "
        f"{filters.get('categories') or 'all'}, minimum plausibility {filters.get('min_plausibility') or 'none'}).",
        "- Edited scenarios come from prompt-driven edits of real or synthetic logs; every other agent was "
        "re-simulated around the edit by the reactive traffic model, and every exported scenario was re-validated "
        "from its exported tracks (collisions, leaving the road, kinematic limits of the changed agents).",
        f"- Layout: {layout.get('steps')} steps at {layout.get('hz')} Hz, current step {layout.get('current_index')}; "
        "longer logs are cut into windows, shorter ones padded with invalid steps (the manifest's per-scenario "
        "`notes` say what was resampled, cut or padded).",
        f"- Splits by source log (no log's variants cross splits): {manifest.get('splits', {})}.",
        "- Coordinates: metres in each log's world frame (the ego's first pose), headings in radians.",
        "- Track ids are the source's integer ids where it has them; the manifest maps every object id to its "
        "track id.",
        "",
        "## Formats",
        "",
        *[f"- {FORMAT_NOTES[f]}" for f in manifest.get("formats", []) if f in FORMAT_NOTES],
        "",
        "## Contents",
        "",
        *_table("split", counts.get("by_split", {})),
        *_table("category", counts.get("by_category", {})),
        *_table("log source", counts.get("by_log_source", {})),
        "| agent type | tracks |",
        "|---|---:|",
        *[f"| {k} | {v} |" for k, v in sorted(counts.get("by_agent_type", {}).items())],
        "",
        f"Left out after re-validation: {len(manifest.get('left_out', {}))} scenario(s) (reasons in the manifest).",
        "",
        "## Licences",
        "",
        "The scenarios derive from logs under these terms; the dataset inherits them:",
        "",
        *[f"- `{source}`: {text}" for source, text in sorted(manifest.get("licences", {}).items())],
        "",
    ]
    return "\n".join(lines)
