"""``EditorOptions``: what an editor may do, so restricted editors (the paper's baselines) are this editor
with options, not separate code.

* ``grounding``: ``"language"`` (the ``QueryEngine`` with appearance, motion and location), ``"attributes"``
  (category and colour only: the engine with motion and location switched off, ChatSim-like) or ``"ids"``
  (targets and anchors by node / object id only, OmniRe-like);
* ``ops``: the allowed ops; ``relations``: the allowed placement relations;
* ``allow_pedestrian_insert``;
* ``refinement``: how the traffic reacts to the edit (``motion.refine``): ``"full"`` (every other agent is
  driven by the motion predictor), ``"single-agent"`` (only the edited agents avoid conflicts) or ``"none"``
  (everyone else replays the log: deterministic editing, ``simsplat edit --no-refine``);
* ``ego_reacts``: the ego reacts too in refinement (``"full"`` mode): it brakes for what the edit put in its
  way, and the renders follow it (the cameras carried to its new poses along, or near, its logged path:
  ``editing.renders.frame_views``). On by default: an ego replaying its log drives through an obstacle put on
  its path. Off (``simsplat edit --ego-replays``), the renders come from the log's own camera poses, the views
  the scene was reconstructed from;
* ``check_looks``: render inserted objects asked in an achromatic colour and match their exposure
  (``editing.assets.look_check``); off where only trajectories matter (the motion benchmark).

:data:`CHATSIM_LIKE` and :data:`OMNIRE_LIKE` are the two restricted editors of the evaluation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, get_args

from simsplat_core.editing.commands import EditCommand, Op, Relation
from simsplat_core.editing.result import EditRefused
from simsplat_core.motion.refine import REFINE_MODES

GroundingMode = Literal["language", "attributes", "ids"]
ALL_OPS: frozenset[str] = frozenset(get_args(Op))
ALL_RELATIONS: frozenset[str] = frozenset(get_args(Relation))


@dataclass(frozen=True)
class EditorOptions:
    """Restrictions of an editor (module docstring). The defaults allow everything."""

    grounding: GroundingMode = "language"
    ops: frozenset[str] = field(default=ALL_OPS)
    relations: frozenset[str] = field(default=ALL_RELATIONS)
    allow_pedestrian_insert: bool = True
    name: str = "ours"
    refinement: str = "full"
    ego_reacts: bool = True
    check_looks: bool = True

    def __post_init__(self) -> None:
        if self.grounding not in get_args(GroundingMode):
            raise ValueError(f"EditorOptions.grounding must be one of {list(get_args(GroundingMode))}, "
                             f"got {self.grounding!r}")
        if self.refinement not in REFINE_MODES:
            raise ValueError(f"EditorOptions.refinement must be one of {list(REFINE_MODES)}, got {self.refinement!r}")
        object.__setattr__(self, "ops", frozenset(self.ops))
        object.__setattr__(self, "relations", frozenset(self.relations))
        for name, given, known in (("ops", self.ops, ALL_OPS), ("relations", self.relations, ALL_RELATIONS)):
            unknown = sorted(given - known)
            if unknown:
                raise ValueError(f"EditorOptions.{name}: unknown {unknown}; known {sorted(known)}")

    def check(self, command: EditCommand, index: int | None = None) -> None:
        """Raise ``EditRefused("unsupported")`` when ``command`` needs something this editor does not allow
        (the category of an inserted asset is checked once it is known: :meth:`check_insert_category`)."""
        if command.op not in self.ops:
            raise EditRefused(f"the {self.name} editor does not {command.op} objects (it supports: "
                              f"{', '.join(sorted(self.ops))})", reason="unsupported", command_index=index)
        placement = command.placement
        if placement is not None and placement.relation not in self.relations:
            raise EditRefused(f"the {self.name} editor cannot place objects '{placement.relation}' (placements it "
                              f"supports: {', '.join(sorted(self.relations))})", reason="unsupported",
                              command_index=index)
        if command.asset is not None and command.op == "insert" and command.asset.category == "pedestrian":
            self.check_insert_category("pedestrian", index)

    def check_insert_category(self, category: str, index: int | None = None) -> None:
        if category == "pedestrian" and not self.allow_pedestrian_insert:
            raise EditRefused(f"the {self.name} editor cannot insert pedestrians", reason="unsupported",
                              command_index=index)


#: This editor: everything allowed.
DEFAULT_OPTIONS = EditorOptions()
#: ChatSim-like: colour / type attribute matching, insert and remove only, fixed placement modes.
CHATSIM_LIKE = EditorOptions(grounding="attributes", ops=frozenset({"insert", "remove"}),
                             relations=frozenset({"in_lane", "in_front_of", "behind", "absolute"}),
                             name="chatsim-like", ego_reacts=False)
#: OmniRe-like: object ids instead of language grounding, no pedestrian insertion.
OMNIRE_LIKE = EditorOptions(grounding="ids", allow_pedestrian_insert=False, name="omnire-like", ego_reacts=False)
