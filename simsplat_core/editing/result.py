"""What an edit produces: the edited scene by value, the delta on the stored scene, and refusals.

``apply_edit`` never changes its inputs: :class:`EditedScene` holds the original graph and the edited one
(sharing every unchanged node), the agents' states after the edit and the delta that, applied to the
stored scene, gives the edited one (what ``edits/<run>/<seq>/<edit>/delta/`` persists: no Gaussians of
existing nodes are copied).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from simsplat_core.editing.commands import EditCommand
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.pose_track import PoseTrack
from simsplat_core.scene_view import ego_pose_moved

if TYPE_CHECKING:
    from simsplat_core.motion.refine import Refinement
    from simsplat_core.scenario.metrics import ValidationReport

#: The editor's timed stages (``EditedScene.seconds``), in order.
EDIT_STAGES: tuple[str, ...] = ("ground", "apply", "refine", "validate")
#: ``EditRefused.reason`` codes (stable: the ``edits`` table's ``failure_reason`` starts with one).
REFUSAL_REASONS: tuple[str, ...] = (
    "unsupported",  # the words ask for something the command language cannot express
    "not_found",  # the target / anchor description matches nothing in the scene
    "no_asset",  # no asset in the bank fits the description
    "infeasible_placement",  # e.g. a car on the sidewalk, no lane where asked
    "infeasible_motion",  # e.g. turning without an intersection ahead, reversing a pedestrian
    "wrong_category",  # e.g. a lane change for a pedestrian
    "invalid_command",  # the command failed schema validation
)


class EditRefused(ValueError):
    """An edit that cannot be carried out. ``str(error)`` says what is missing and what is supported.

    Attributes:
        reason: one of :data:`REFUSAL_REASONS`.
        command_index: which command of the program failed (``None``: the prompt as a whole).
    """

    def __init__(self, message: str, *, reason: str, command_index: int | None = None) -> None:
        if reason not in REFUSAL_REASONS:
            raise ValueError(f"EditRefused: unknown reason {reason!r}; expected one of {list(REFUSAL_REASONS)}")
        super().__init__(message)
        self.reason = reason
        self.command_index = command_index


@dataclass(frozen=True, eq=False)
class AddedNode:
    """A node the edit added: its id in the edited graph, the asset it came from and its own pose track.

    ``arc_length`` (``[T]`` metres along the new path at ``track.times``, or ``None``) retimes a
    pedestrian asset's gait to the new path (``editing.assets.nodes.asset_node``).
    """

    node_id: int
    object_id: str
    asset_id: str
    category: str
    track: PoseTrack
    arc_length: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class EditDelta:
    """The edited scene as a change of the stored one.

    Attributes:
        removed_node_ids: nodes dropped (removed objects, and the old node of a replaced one).
        added: nodes added (inserted objects, the new appearance of replaced ones).
        retracked: new pose tracks of existing nodes (modified trajectories), by node id.
    """

    removed_node_ids: tuple[int, ...] = ()
    added: tuple[AddedNode, ...] = ()
    retracked: dict[int, PoseTrack] = field(default_factory=dict)

    @property
    def is_empty(self) -> bool:
        return not (self.removed_node_ids or self.added or self.retracked)


@dataclass(frozen=True)
class CommandOutcome:
    """What one command did.

    Attributes:
        command: the command as applied (after defaults were filled in).
        target_node_ids: nodes the target grounded to (empty for inserts).
        anchor_node_ids: nodes the placement anchor grounded to (empty: ego / absolute / none).
        new_object_ids: agents the command added.
        changed_object_ids: agents whose trajectory or appearance changed (or that were removed).
        summary: one line for people ("removed node 12 (white van)").
    """

    command: EditCommand
    target_node_ids: tuple[int, ...] = ()
    anchor_node_ids: tuple[int, ...] = ()
    new_object_ids: tuple[str, ...] = ()
    changed_object_ids: tuple[str, ...] = ()
    summary: str = ""


@dataclass(frozen=True, eq=False)
class EditedScene:
    """The result of ``apply_edit``.

    Attributes:
        prompt: the words (``""`` for a command-only edit).
        original: the graph edited (unchanged).
        graph: the edited graph (by value; unchanged nodes are shared).
        original_states / states: agents before / after (``states.sources`` marks edited and inserted rows).
        delta: the change on the stored scene.
        outcomes: one per command, in order.
        validation: collisions, off-road and kinematics of the edited and refined agents (``scenario.metrics``).
        refinement: how the other agents reacted (``None``: not refined, everyone else replays the log).
        seconds: wall seconds of the editor's stages (:data:`EDIT_STAGES`: grounding the targets and anchors,
            applying the commands -- placement, motion planning, building the graph, the look check --, the
            traffic's refinement, validation; re-applications summed); recorded, never read by the editor.
    """

    prompt: str
    original: SceneGraph
    graph: SceneGraph
    original_states: AgentStates
    states: AgentStates
    delta: EditDelta
    outcomes: tuple[CommandOutcome, ...]
    validation: ValidationReport
    refinement: Refinement | None = None
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def commands(self) -> tuple[EditCommand, ...]:
        return tuple(o.command for o in self.outcomes)

    def ego_poses(self, log_poses: np.ndarray, tol_m: float = 1e-3) -> dict[int, np.ndarray]:
        """Frame index -> ``[4, 4]`` ego pose where the edit moved the ego (refinement with ``ego_reacts``), from
        the log's ``log_poses [T, 4, 4]``; empty when the ego replays its log."""
        before, after = self.original_states, self.states
        if EGO_ID not in after.object_ids or EGO_ID not in before.object_ids:
            return {}
        i, j = before.index(EGO_ID), after.index(EGO_ID)
        moved = np.flatnonzero(np.linalg.norm(after.xy[j] - before.xy[i], axis=-1) > tol_m)
        return {int(after.frame_idx[k]): ego_pose_moved(log_poses[int(after.frame_idx[k])], after.xy[j, k],
                                                        float(after.heading[j, k])) for k in moved}

    def summary_lines(self) -> list[str]:
        return [o.summary for o in self.outcomes if o.summary]

    def as_dict(self) -> dict[str, Any]:
        """JSON-able summary: prompt, commands, per-command grounded ids and summaries, validation."""
        return {
            "prompt": self.prompt,
            "commands": [o.command.model_dump(mode="json") for o in self.outcomes],
            "outcomes": [{"target_node_ids": list(o.target_node_ids), "anchor_node_ids": list(o.anchor_node_ids),
                          "new_object_ids": list(o.new_object_ids), "changed_object_ids": list(o.changed_object_ids),
                          "summary": o.summary} for o in self.outcomes],
            "validation": self.validation.as_dict(),
        }
