"""Apply an :class:`~simsplat_core.editing.result.EditDelta` to a scene graph, by value.

``apply_edit`` builds its edited graph with this function, and so does anyone rebuilding a stored edit
from the stored scene and the asset bank (``storage.edits.read_edit_delta``): one code path, so a rebuilt
edit equals the edit as it was applied.

Order: removed nodes are dropped, re-tracked nodes get their new pose tracks, added nodes are built by
``node_for`` (an asset's Gaussians on the added node's track) and added with their own tracks.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from simsplat_core.editing.result import AddedNode, EditDelta
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.nodes import ObjectNode

logger = logging.getLogger(__name__)

#: Builds the node of an added object (``AddedNode`` -> ``ObjectNode`` with ``node_id == added.node_id``); the
#: editor and the rebuild both use ``editing.assets.nodes.asset_node`` on the bank's asset.
NodeFactory = Callable[[AddedNode], ObjectNode]


def check_delta(graph: SceneGraph, delta: EditDelta) -> None:
    """Raise ``ValueError`` (naming the node) unless ``delta`` applies to ``graph``: removed and re-tracked ids
    are object nodes of the graph, disjoint, and added ids are new and distinct."""
    known = {n.node_id for n in graph.object_nodes}
    for what, ids in (("removed", delta.removed_node_ids), ("re-tracked", tuple(delta.retracked))):
        missing = sorted(set(ids) - known)
        if missing:
            raise ValueError(f"edit delta: {what} node(s) {missing} are not object nodes of the graph "
                             f"(object nodes {sorted(known)})")
    both = sorted(set(delta.removed_node_ids) & set(delta.retracked))
    if both:
        raise ValueError(f"edit delta: node(s) {both} are both removed and re-tracked")
    added = [a.node_id for a in delta.added]
    clash = sorted({n for n in added if n in {m.node_id for m in graph.nodes}} | {n for n in added
                                                                                 if added.count(n) > 1})
    if clash:
        raise ValueError(f"edit delta: added node id(s) {clash} are taken or repeated")


def apply_delta(graph: SceneGraph, delta: EditDelta, node_for: NodeFactory) -> SceneGraph:
    """The graph with ``delta`` applied (``graph`` is not changed; unchanged nodes are shared).

    Raises:
        ValueError: the delta does not apply to ``graph`` (:func:`check_delta`), or ``node_for`` returned a
            node with another id than asked.
    """
    check_delta(graph, delta)
    out = graph.without(delta.removed_node_ids) if delta.removed_node_ids else graph
    for node_id, track in sorted(delta.retracked.items()):
        out = out.with_poses(node_id, track)
    for added in delta.added:
        node = node_for(added)
        if node.node_id != added.node_id:
            raise ValueError(f"edit delta: the node built for {added.object_id!r} has id {node.node_id}, "
                             f"expected {added.node_id}")
        out = out.with_node(node, poses=added.track)
    logger.debug("applied delta: -%s +%s ~%s", list(delta.removed_node_ids), [a.node_id for a in delta.added],
                 sorted(delta.retracked))
    return out
