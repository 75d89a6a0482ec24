"""Room for the traffic: whether the reacting traffic takes an edit without a failure, and where else to try.

An inserted object placed exactly where the prompt says can leave the traffic no way to react: a car put a
few metres in front of a faster one, a barrier inside a moving car's stopping distance, a pedestrian where a
car turning across has already committed. ``editing.apply`` then tries the inserted rows a little further
ahead or back along their lanes (shares :data:`ROOM_SHIFTS` of :func:`room_reach`: a fifth of an asked
distance, at least 1.5 m, so that a said distance still reads as said; 2 m when none was said) and keeps
the first spot where :func:`traffic_copes`; when none does, the spot as asked, whose failures the validation
reports.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.editing.commands import EditCommand, EditProgram
from simsplat_core.editing.draft import Draft
from simsplat_core.motion.refine import EDIT_SOURCES
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.metrics import validate_agents

#: Shares of an inserted row's placement reach tried, in order, after the asked spot (share 0).
ROOM_SHIFTS: tuple[float, ...] = (0.5, -0.5, 1.0, -1.0)
#: The room search moves an inserted row at most this share of a said distance (at least ``ROOM_MIN_M``), m: a
#: car asked 20 m ahead stays within 16-24 m; one asked 5 m behind within 3.5-6.5 m.
ROOM_DISTANCE_SHARE = 0.2
ROOM_MIN_M = 1.5


#: ... and at most this far (m) when no distance was said ("next to the man", "behind the bus"): a step, not
#: another spot.
ROOM_UNSAID_M = 2.0


def room_reach(distance_m: float | None) -> float:
    """How far (m) the room search may move an inserted row placed ``distance_m`` from its anchor (``None``: the
    prompt said no distance)."""
    if distance_m is None:
        return ROOM_UNSAID_M
    return max(ROOM_MIN_M, ROOM_DISTANCE_SHARE * abs(distance_m))


def searches_room(program: EditProgram, refinement: str) -> bool:
    """Whether an edit may move its inserted objects for the traffic: it inserts something at a relative spot (an
    absolute position is taken as given) and the traffic reacts (``refinement`` other than ``"none"``, whose
    other agents replay their log whatever happens)."""
    return refinement != "none" and any(movable(c) for c in program.commands)


def movable(command: EditCommand) -> bool:
    """Whether ``command`` inserts something the room search may move: not at an absolute position."""
    return command.op == "insert" and (command.placement is None or command.placement.position is None)


def changed_rows(states: AgentStates) -> np.ndarray:
    """``[R]`` rows of the edited, inserted and reacting (``"refined"``) agents."""
    return np.flatnonzero([s in (*EDIT_SOURCES, "refined") for s in states.sources]).astype(np.int64)


def traffic_copes(draft: Draft) -> bool:
    """Whether every edited, inserted and reacting agent of ``draft`` is free of collisions, off-road and
    kinematic failures that the unedited scene did not already have."""
    return validate_agents(draft.states, draft.ctx.map_ctx, changed_rows(draft.states), baseline=draft.ctx.states).ok
