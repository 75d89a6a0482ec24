"""The answers of the interactive commands as plain JSON-able data: what ``simsplat query | search | edit | mine
--json`` print as one JSON object (scripts read them; field names are part of the interface).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict
from typing import TYPE_CHECKING, Any

from simsplat_core.language.grounding.result import NodeMatch
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.search.logs import StoreSearch

if TYPE_CHECKING:  # the task modules load Prefect and the editing core: only their result types are needed here
    from simsplat_core.scene import SceneGraph
    from tasks.edit import EditRun
    from tasks.mine import MiningSummary
    from tasks.query import QueryAnswer


def _finite(value: float) -> float | None:
    """``value`` as a JSON number, ``None`` for a signal the query did not use (``nan``)."""
    return round(float(value), 6) if math.isfinite(value) else None


def node_labels(node: NodeLanguage) -> dict[str, str | None]:
    """What a language scene says of one object node: ``caption`` (``None`` without pixels), ``motion`` (the
    aligner's class), ``motion_label`` and ``location_label`` (the auto-labels; ``None`` for static objects)."""
    motion = node.motion
    return {
        "caption": node.caption.text if node.caption is not None else None,
        "motion": motion.motion if motion is not None else None,
        "motion_label": motion.labels.motion if motion is not None else None,
        "location_label": f"{motion.labels.sector} {motion.labels.context}" if motion is not None else None,
    }


def _match_dict(scene: LanguageScene, match: NodeMatch, chosen: bool) -> dict[str, Any]:
    node = scene.node(match.node_id)
    return {
        "node_id": match.node_id,
        "object_id": match.object_id,
        "category": node.category,
        **node_labels(node),
        "scores": {"score": _finite(match.score), "appearance": _finite(match.appearance),
                   "motion": _finite(match.motion), "location": _finite(match.location)},
        "candidate": match.candidate,
        "chosen": chosen,
    }


def answer_as_dict(answer: QueryAnswer, top: int | None = None) -> dict[str, Any]:
    """The answer as plain JSON-able data (``simsplat query --json``).

    Keys: ``seq_id``, ``query``, ``matches`` (the chosen nodes, best first), ``ranking`` (the first ``top``
    scored nodes; all when ``None``), ``message``, ``group``, ``frame`` and ``png`` (``None`` when nothing was
    drawn). Each node: ``node_id``, ``object_id``, ``category``, ``caption`` (``None`` without images),
    ``motion`` (the aligner's class), ``motion_label`` / ``location_label`` (the auto-labels), ``scores``
    (``score``, ``appearance``, ``motion``, ``location``; ``None`` for a signal the query did not use),
    ``candidate`` and ``chosen``.
    """
    grounding, scene = answer.grounding, answer.scene
    chosen = set(grounding.node_ids)
    ranking = grounding.ranking if top is None else grounding.ranking[:top]
    return {
        "seq_id": scene.seq_id,
        "query": grounding.query,
        "matches": [_match_dict(scene, m, True) for m in grounding.matches],
        "ranking": [_match_dict(scene, m, m.node_id in chosen) for m in ranking],
        "message": grounding.message,
        "group": grounding.group,
        "frame": answer.frame,
        "png": answer.png_uri or None,
    }


def search_as_dict(found: StoreSearch) -> dict[str, Any]:
    """``simsplat search --json``: ``query``, ``clauses``, ``hits`` (``seq_id``, ``object_ids``, ``window``
    [start, end], ``score``, ``picture`` or ``None``, ``picture_kind``), ``message``, ``seconds``."""
    return {
        "query": found.query.text,
        "clauses": [c.text for c in found.query.clauses],
        "hits": [{"seq_id": h.seq_id, "object_ids": list(h.object_ids), "window": list(h.window),
                  "score": round(h.score, 6), "picture": h.picture or None,
                  "picture_kind": found.picture_kinds.get(h.picture)} for h in found.hits],
        "message": found.message,
        "seconds": round(found.seconds, 4),
    }


def edit_as_dict(run: EditRun, graph: SceneGraph | None = None) -> dict[str, Any]:
    """The attempt as plain JSON-able data (``simsplat edit --json``): ``status``, ``seq_id``, ``run_id``,
    ``edit_id``, ``edit_dir``, ``prompt``, ``commands``, ``grounded`` (per command: target / anchor node and
    object ids), ``changes``, ``new_object_ids``, ``validation``, ``reason`` / ``message`` of a refusal,
    ``seconds`` and ``bytes``."""
    object_of = {n.node_id: n.object_id for n in graph.object_nodes} if graph is not None else {}
    out: dict[str, Any] = {
        "status": run.status, "seq_id": run.seq_id, "run_id": run.run_id, "edit_id": run.edit_id,
        "edit_dir": run.edit_uri or None, "prompt": run.prompt,
        "commands": [c.model_dump(mode="json") for c in run.program.commands] if run.program is not None else [],
        "grounded": [], "changes": [], "new_object_ids": [], "validation": None, "refinement": None,
        "reason": run.reason or None, "message": run.message or None,
        "seconds": {k: round(v, 3) for k, v in run.seconds.items()}, "bytes": run.bytes, "skipped": run.skipped,
    }
    if run.edited is not None:
        for k, o in enumerate(run.edited.outcomes):
            out["grounded"].append({
                "command": k, "op": o.command.op,
                "target_node_ids": list(o.target_node_ids),
                "target_object_ids": [object_of.get(n, "") for n in o.target_node_ids],
                "anchor_node_ids": list(o.anchor_node_ids),
                "anchor_object_ids": [object_of.get(n, "") for n in o.anchor_node_ids]})
            out["changes"].append(o.summary)
            out["new_object_ids"] += list(o.new_object_ids)
        out["validation"] = run.edited.validation.as_dict()
        reaction = run.edited.refinement
        out["refinement"] = None if reaction is None else {
            "mode": reaction.mode, "predictor": reaction.predictor, "start_step": reaction.start_step,
            "refined": list(reaction.refined_ids), "replayed": dict(sorted(reaction.replayed.items()))}
    return out


def mining_as_dict(run_id: str, summaries: Sequence[MiningSummary]) -> dict[str, Any]:
    """``simsplat mine --json``: ``run_id``, ``edits_table``, ``scenarios`` (the accepted ones), ``sequences``
    (per-sequence summaries) and ``totals``."""
    sequences = [{k: v for k, v in asdict(s).items() if k != "scenarios"} for s in summaries]
    for entry in sequences:
        entry["seconds"] = {k: round(v, 3) for k, v in entry["seconds"].items()}
    categories: dict[str, int] = {}
    for s in summaries:
        for category, n in s.per_category.items():
            categories[category] = categories.get(category, 0) + n
    attempts = sum(s.attempts for s in summaries)
    accepted = sum(s.accepted for s in summaries)
    return {"run_id": run_id, "edits_table": summaries[0].edits_table if summaries else None,
            "scenarios": [asdict(sc) for s in summaries for sc in s.scenarios], "sequences": sequences,
            "totals": {"sequences": len(summaries), "attempts": attempts, "accepted": accepted,
                       "per_category": dict(sorted(categories.items()))}}
