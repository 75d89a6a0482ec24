"""Ground an edit's targets and anchors (``TargetRef``) to scene-graph nodes, or refuse with a clear message.

    grounder = Grounder(language_scene, engine, graph, mode="language")
    found = grounder.ground(TargetRef(description="the white van"), command_index=0)
    found.node_ids, found.object_ids, found.message

* ``description``: ``QueryEngine.ground`` (mode ``"language"``), or the engine with motion and location
  switched off (``"attributes"``: category and colour only); mode ``"ids"`` refuses descriptions.
  ``group=True`` asks the engine for every match ("all parked cars").
* ``node_id`` / ``object_id``: the graph's object node (any mode).
* "the lead vehicle" / "the leading car" (:data:`LEAD_RX`), given the log's agents and lanes: the nearest moving
  vehicle ahead of the ego in its lane (``scenario.lead.lead_vehicle``), found by geometry, not by words.

Nothing found is ``EditRefused(reason="not_found")`` whose message is the engine's ("no purple bus in this
scene") plus what similar objects the scene has. Nodes an earlier command removed are not found again.

An edit acts on what it names: a search may rank the nearest colour first ("the purple van" -> a blue van),
an edit may not. Matches whose caption contradicts a colour the description names are dropped
(:func:`colors_agree`; neighbouring greys agree, captions being unsure of them); when none is left the
reference is refused as not found.
"""

from __future__ import annotations

import dataclasses
import logging
import re
from collections import Counter
from collections.abc import Collection
from dataclasses import dataclass

from simsplat_core.color_names import ACHROMATIC_NAMES
from simsplat_core.editing.commands import TargetRef
from simsplat_core.editing.options import GroundingMode
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.grounding.parse import ParsedQuery, parse_query
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.lead import lead_vehicle
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.stage_clock import StageClock, maybe_stage

logger = logging.getLogger(__name__)

#: Similar objects named in a not-found message.
SIMILAR_SHOWN = 3
#: A description of the lead vehicle (the whole description names it: "the lead vehicle", "the leading car").
LEAD_RX = re.compile(r"^(?:the )?(?:lead|leading) (?:vehicle|car)$")


def _same_color(asked: str, seen: str) -> bool:
    """``asked`` and ``seen`` name the same colour, or neighbouring achromatic ones (white / silver / gray /
    black are told apart by brightness, which lighting shifts by a step)."""
    if asked == seen:
        return True
    if asked in ACHROMATIC_NAMES and seen in ACHROMATIC_NAMES:
        return abs(ACHROMATIC_NAMES.index(asked) - ACHROMATIC_NAMES.index(seen)) == 1
    return False


def colors_agree(parsed: ParsedQuery, caption: AppearanceCaption | None) -> bool:
    """Whether ``caption`` can be the object ``parsed`` describes by colour: every named colour (the main colour,
    or the upper / lower clothing colours) is among the caption's (no caption: nothing contradicts)."""
    if caption is None:
        return True
    pairs = [(parsed.upper_color, caption.upper_color), (parsed.lower_color, caption.lower_color)]
    for asked, seen in pairs:
        if asked is not None and seen is not None and not _same_color(asked, seen):
            return False
    seen_colors = caption.colors
    return all(any(_same_color(asked, seen) for seen in seen_colors) for asked in parsed.colors) if seen_colors \
        else True


@dataclass(frozen=True)
class Grounded:
    """Nodes a reference grounded to: ``node_ids`` / ``object_ids`` (same order, best first) and the
    engine's message (or how the id was resolved)."""

    node_ids: tuple[int, ...]
    object_ids: tuple[str, ...]
    message: str


class Grounder:
    """Grounds ``TargetRef`` s in one scene (module docstring).

    Args:
        language: the language scene of ``graph`` (its object nodes, captions, motion features).
        engine: the grounding engine.
        graph: the graph being edited (ids are checked against its object nodes).
        mode: the editor's grounding mode.
        clock: where :meth:`ground` adds its wall seconds (stage ``"ground"``; ``None``: not timed).
        states, lanes: the log's agents and lane graph (both given: "the lead vehicle" is grounded by geometry).
    """

    def __init__(self, language: LanguageScene, engine: QueryEngine, graph: SceneGraph,
                 mode: GroundingMode = "language", clock: StageClock | None = None, *,
                 states: AgentStates | None = None, lanes: LaneGraph | None = None) -> None:
        self.language = language
        self.clock = clock
        self.graph = graph
        self.mode = mode
        self.states = states
        self.lanes = lanes
        if mode == "attributes":
            engine = engine.with_config(dataclasses.replace(engine.config, use_motion=False, use_location=False))
        self.engine = engine
        self._objects = {n.node_id: n for n in graph.object_nodes}

    def describe(self, node_id: int) -> str:
        """``"veh_02 (node 16): a white van"`` (the caption when the language scene has one)."""
        node = self._objects[node_id]
        caption = ""
        try:
            entry = self.language.node(node_id)
            caption = entry.caption.text if entry.caption is not None else ""
        except KeyError:
            pass
        return f"{node.object_id} (node {node_id})" + (f": {caption}" if caption else f": a {node.category}")

    def ground(self, ref: TargetRef, *, removed: Collection[int] = (), command_index: int | None = None,
               role: str = "target") -> Grounded:
        """The nodes ``ref`` names that still exist (not in ``removed``).

        Raises:
            EditRefused: ``not_found`` (nothing matches, or only removed nodes), ``unsupported`` (a
                description in ``"ids"`` mode).
        """
        with maybe_stage(self.clock, "ground"):
            return self._ground(ref, removed, command_index, role)

    def _ground(self, ref: TargetRef, removed: Collection[int], command_index: int | None, role: str) -> Grounded:
        if ref.is_ego:
            raise EditRefused(f"the ego vehicle cannot be a {role} here", reason="unsupported",
                              command_index=command_index)
        if ref.node_id is not None or ref.object_id is not None:
            return self._by_id(ref, removed, command_index, role)
        assert ref.description is not None
        if self.states is not None and self.lanes is not None and self.mode != "ids" \
                and LEAD_RX.match(" ".join(ref.description.lower().split())):
            return self._lead(self.states, self.lanes, removed, command_index, role)
        if self.mode == "ids":
            raise EditRefused(f"this editor takes object ids, not descriptions: give the {role} as a node id or "
                              f"object id instead of {ref.description!r}", reason="unsupported",
                              command_index=command_index)
        text = ref.description.strip()
        if ref.group and not parse_query(text).group:
            text = f"all {text}"
        grounding = self.engine.ground(self.language, text)
        gone = set(removed)
        alive = [m for m in grounding.matches if m.node_id in self._objects and m.node_id not in gone]
        parsed = parse_query(text)
        agreeing = [m for m in alive if colors_agree(parsed, self._caption(m.node_id))]
        if alive and not agreeing:
            asked = " / ".join(c for c in (*parsed.colors, parsed.upper_color, parsed.lower_color) if c)
            message = self._not_found(f"no {asked} {parsed.noun or 'object'} matching {ref.description!r} in this "
                                      "scene", [m.node_id for m in grounding.ranking], gone)
            raise EditRefused(message, reason="not_found", command_index=command_index)
        alive = agreeing
        if not alive:
            if grounding.matches:
                message = (f"{ref.description!r} is {', '.join(self.describe(m.node_id) for m in grounding.matches)}"
                           ", which an earlier command already removed")
            else:
                message = self._not_found(grounding.message, [m.node_id for m in grounding.ranking], gone)
            raise EditRefused(message, reason="not_found", command_index=command_index)
        ids = tuple(m.node_id for m in alive)
        logger.info("%s %r -> %s", role, ref.description, ids)
        return Grounded(ids, tuple(self._objects[i].object_id for i in ids), grounding.message)

    def _lead(self, states: AgentStates, lanes: LaneGraph, removed: Collection[int], command_index: int | None,
              role: str) -> Grounded:
        """The lead vehicle's node (module docstring), or ``EditRefused`` (``not_found``) saying there is none."""
        row = lead_vehicle(states, lanes, self.language.seq_id)
        node = None if row is None else next(
            (n for n in self._objects.values() if n.object_id == states.object_ids[row]), None)
        if node is None:
            raise EditRefused("no lead vehicle in this scene: no moving vehicle is ahead of the ego in its lane",
                              reason="not_found", command_index=command_index)
        if node.node_id in set(removed):
            raise EditRefused(f"the lead vehicle, {self.describe(node.node_id)}, was already removed by an earlier "
                              "command", reason="not_found", command_index=command_index)
        logger.info("%s 'the lead vehicle' -> %s", role, node.node_id)
        return Grounded((node.node_id,), (node.object_id,), f"{role}: the lead vehicle, {self.describe(node.node_id)}")

    def _caption(self, node_id: int) -> AppearanceCaption | None:
        try:
            return self.language.node(node_id).caption
        except KeyError:
            return None

    def _by_id(self, ref: TargetRef, removed: Collection[int], command_index: int | None, role: str) -> Grounded:
        if ref.node_id is not None:
            node = self._objects.get(ref.node_id)
            asked = f"node {ref.node_id}"
        else:
            node = next((n for n in self._objects.values() if n.object_id == ref.object_id), None)
            asked = f"object {ref.object_id!r}"
        if node is None:
            known = ", ".join(f"{n.object_id} (node {n.node_id})" for n in list(self._objects.values())[:12])
            raise EditRefused(f"no {asked} in this scene; objects: {known}"
                              f"{' ...' if len(self._objects) > 12 else ''}", reason="not_found",
                              command_index=command_index)
        if node.node_id in set(removed):
            raise EditRefused(f"{asked} was already removed by an earlier command", reason="not_found",
                              command_index=command_index)
        return Grounded((node.node_id,), (node.object_id,), f"{role} by id: {self.describe(node.node_id)}")

    def _not_found(self, message: str, ranked: list[int], gone: set[int]) -> str:
        """The engine's message plus the closest objects (or, with none of the category, what the scene has)."""
        similar = [i for i in ranked if i in self._objects and i not in gone][:SIMILAR_SHOWN]
        if similar:
            return f"{message}; closest: " + "; ".join(self.describe(i) for i in similar)
        counts = Counter(n.category for i, n in self._objects.items() if i not in gone)
        have = ", ".join(f"{k} {c}{'s' if k != 1 else ''}" for c, k in counts.most_common())
        return f"{message}; this scene has {have or 'no objects'}"
