"""The records one edit works on: what it reads (``EditContext``) and its working copy of the scene (``Draft``).

``editing.apply`` creates the draft from the context, the edit ops (``editing.ops``) change it command by
command, the traffic's reaction (``editing.traffic``) writes the refined agents back into it, and
:meth:`Draft.delta` is the :class:`~simsplat_core.editing.result.EditDelta` of it all. Every module of the
editing pipeline reads these records from here, so none of them imports another to reach them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.commands import AssetSpec
from simsplat_core.editing.grounding import Grounder
from simsplat_core.editing.options import EditorOptions
from simsplat_core.editing.result import AddedNode, EditDelta, EditRefused
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.grounding.static_location import with_static_locations
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.motion.motion_map import motion_map_of
from simsplat_core.motion.predictor import MotionMap, MotionPredictor
from simsplat_core.motion.registry import default_predictor
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.pose_track import PoseTrack
from simsplat_core.types import SceneLog

if TYPE_CHECKING:
    from simsplat_core.motion.refine import Refinement

#: ``object_id`` prefix of inserted agents (``inserted_00``, ``inserted_01``, ...).
INSERTED_PREFIX = "inserted_"


@dataclass(frozen=True, eq=False)
class EditContext:
    """Everything an edit reads, none of it changed by editing.

    Attributes:
        log: the sequence's log (tracks, ego poses, map, cameras; no images needed).
        graph: the stored scene graph (for a log without images: the graph of its tracks, ``scene.track_graph``).
        language: the graph's language scene (what grounding reads), static objects' sectors filled in from the
            log (``language.grounding.static_location``).
        engine: the grounding engine (its text encoder also retrieves assets and parses prompts).
        bank: the asset bank (``None``: inserts and replacements are refused, naming ``simsplat assets build``).
        lanes: the log's lane graph.
        map_ctx: the log's map for point queries.
        states: every agent of the log (ego included) on the log's frames, with their node ids.
        motion_map: the map the motion predictor drives on (refinement).
        predictor: the motion predictor of refinement (``None``: the default reactive traffic model).
    """

    log: SceneLog
    graph: SceneGraph
    language: LanguageScene
    engine: QueryEngine
    bank: AssetBank | None
    lanes: LaneGraph
    map_ctx: MapContext
    states: AgentStates
    motion_map: MotionMap
    predictor: MotionPredictor | None = None

    @classmethod
    def create(cls, log: SceneLog, graph: SceneGraph, language: LanguageScene, engine: QueryEngine,
               bank: AssetBank | None, predictor: MotionPredictor | None = None) -> EditContext:
        """The context of ``graph`` (reconstructed from ``log``): lane graph, map context and agent states
        derived from the log.

        Raises:
            StaleSceneError: ``language`` describes another revision of the graph.
        """
        language.check_graph(graph)
        node_of_object = {n.object_id: n.node_id for n in graph.object_nodes}
        states = AgentStates.from_log(log, node_of_object)
        motion_map = motion_map_of(log)
        return cls(log=log, graph=graph, language=with_static_locations(language, states), engine=engine, bank=bank,
                   lanes=motion_map.lanes, map_ctx=motion_map.context, states=states, motion_map=motion_map,
                   predictor=predictor)

    def motion_predictor(self) -> MotionPredictor:
        """The predictor refinement uses (the context's, else the default reactive traffic model)."""
        return self.predictor if self.predictor is not None else default_predictor()



@dataclass
class Draft:
    """The scene as it stands after the commands so far: the agents (``AgentStates``), the nodes removed, the
    nodes added (asset references on their own pose tracks) and the new pose tracks of existing nodes.
    Mutable; private to one edit.

    ``removed`` / ``retracked`` / ``added`` make the delta; ``gone`` are the stored nodes a ``remove`` dropped
    (not grounded again); ``replaced`` maps a stored node a ``replace`` swapped to its new node, so later
    commands naming the same object act on the new one. ``room_shift`` moves every inserted row by that share
    of its room search reach (``room.room_reach``) along its lane: ``editing.apply`` tries a few when the
    traffic cannot react to the edit as asked without a crash.
    """

    ctx: EditContext
    grounder: Grounder
    options: EditorOptions
    states: AgentStates
    next_node_id: int
    removed: list[int] = field(default_factory=list)
    added: list[AddedNode] = field(default_factory=list)
    retracked: dict[int, PoseTrack] = field(default_factory=dict)
    assets: dict[str, Asset] = field(default_factory=dict)
    gone: set[int] = field(default_factory=set)
    replaced: dict[int, int] = field(default_factory=dict)
    excluded_assets: frozenset[str] = frozenset()
    refinement: Refinement | None = None
    room_shift: float = 0.0

    @classmethod
    def start(cls, ctx: EditContext, grounder: Grounder, options: EditorOptions,
              excluded_assets: frozenset[str] = frozenset(), room_shift: float = 0.0) -> Draft:
        return cls(ctx=ctx, grounder=grounder, options=options, states=ctx.states,
                   next_node_id=max(n.node_id for n in ctx.graph.nodes) + 1, excluded_assets=excluded_assets,
                   room_shift=room_shift)

    def delta(self) -> EditDelta:
        return EditDelta(removed_node_ids=tuple(self.removed), added=tuple(self.added), retracked=dict(self.retracked))

    # ------------------------------------------------------------------ helpers
    def new_object_id(self) -> str:
        taken = set(self.states.object_ids) | {a.object_id for a in self.added}
        k = 0
        while f"{INSERTED_PREFIX}{k:02d}" in taken:
            k += 1
        return f"{INSERTED_PREFIX}{k:02d}"

    def take_node_id(self) -> int:
        self.next_node_id += 1
        return self.next_node_id - 1

    def retrieve(self, spec: AssetSpec, index: int) -> Asset:
        bank = self.ctx.bank
        if bank is None:
            raise EditRefused("the store has no asset bank to insert or replace objects from: run "
                              "`simsplat assets build --store DIR` first", reason="no_asset", command_index=index)
        try:
            asset = bank.retrieve(spec, self.ctx.engine.text_encoder, exclude=self.excluded_assets)
        except EditRefused as exc:
            raise EditRefused(str(exc), reason=exc.reason, command_index=index) from exc
        self.assets[asset.asset_id] = asset
        return asset

    def row_of(self, object_id: str) -> int:
        return self.states.index(object_id)

    def drop_stored(self, node_id: int) -> None:
        """Take a stored node out of the edited graph (a replaced one: its new node instead)."""
        if node_id in self.replaced:
            new_id = self.replaced.pop(node_id)
            self.added = [a for a in self.added if a.node_id != new_id]
        else:
            self.removed.append(node_id)
            self.retracked.pop(node_id, None)

    def set_track(self, node_id: int, track: PoseTrack) -> None:
        """New pose track of a stored node (of its new node when it was replaced)."""
        if node_id in self.replaced:
            new_id = self.replaced[node_id]
            self.added = [dataclasses.replace(a, track=track, arc_length=None) if a.node_id == new_id else a
                          for a in self.added]
        else:
            self.retracked[node_id] = track

    def describe(self, node_id: int) -> str:
        return self.grounder.describe(node_id)
