"""How an edit changed the traffic: per agent, how far its path moved from the log, how slow it went, and for an
agent the refinement moved (``source == "refined"``) what it did -- detoured, stopped, slowed, sped up -- and which
edited agent it reacted to.

    changes = agent_changes(edited_states, log_states)      # AgentChange per changed agent, edited ones first
    [(c.object_id, c.reaction, c.reacts_to) for c in changes if c.reaction]

Both states are on the log's steps (``AgentStates.from_log``; a stored edit's via
``storage.edits.trajectory_states``). Definitions, kept simple:

* ``max_deviation_m``: the largest distance between an agent's edited and log box centres over the steps valid in
  both (NaN for an agent without a log path: inserted);
* ``path_offset_m``: the largest distance from an edited position to the nearest log position of the agent at any
  step (how far it left its log path, whatever the timing);
* a refined agent's reaction starts at the first step its centre is more than :data:`MOVED_M` from the log's; it
  ``detoured`` when ``path_offset_m`` exceeds :data:`DETOUR_M`, else ``stopped`` when it comes to rest
  (below :data:`STOP_SPEED`) while the log agent kept moving at those steps, else ``slowed`` / ``sped up`` when its
  mean speed over the steps valid in both is :data:`PACE_DELTA` lower / higher than the log's;
* ``reacts_to``: the edited, inserted or removed agent nearest to it at the step its reaction starts (a removed
  agent at its log position).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.agents import AgentStates

#: Centre distance (metres) from the log beyond which a refined agent counts as moved.
MOVED_M = 0.5
#: Path offset (metres) beyond which a moved agent detoured.
DETOUR_M = 1.0
#: Speed (m/s) below which an agent is at rest.
STOP_SPEED = 0.3
#: Mean-speed difference (m/s) from the log that counts as slowing down or speeding up.
PACE_DELTA = 0.5
#: Sources of the edit's own agents (``AgentStates.sources``), and the source given to removed ones.
EDIT_SOURCES: tuple[str, ...] = ("edited", "inserted")
REMOVED = "removed"


@dataclass(frozen=True)
class AgentChange:
    """One agent the edit changed (module docstring for the definitions).

    Attributes:
        object_id, category: the agent.
        source: ``"edited"``, ``"inserted"``, ``"refined"`` or :data:`REMOVED`.
        max_deviation_m: metres (NaN: no log path, or removed).
        path_offset_m: metres (NaN: no log path, or removed).
        min_speed: least absolute speed of its edited path, m/s (NaN: removed).
        log_min_speed: least absolute speed of its log path, m/s (NaN: inserted).
        reaction: ``"detoured"``, ``"stopped"``, ``"slowed"``, ``"sped up"``, ``"moved"`` (none of those) for a
            refined agent; ``""`` for the others.
        reacts_to: the edit's agent it reacts to (``""``: not a reaction, or none to react to).
        reaction_frame: log frame index where its reaction starts (``None``: not a reaction).
    """

    object_id: str
    category: str
    source: str
    max_deviation_m: float
    path_offset_m: float
    min_speed: float
    log_min_speed: float
    reaction: str = ""
    reacts_to: str = ""
    reaction_frame: int | None = None


def _min_abs(values: np.ndarray) -> float:
    return float(np.abs(values).min()) if values.size else math.nan


def _reaction(edited: AgentStates, log: AgentStates, k: int, j: int, path_offset: float) -> str:
    both = edited.valid[k] & log.valid[j]
    if path_offset > DETOUR_M:
        return "detoured"
    mine, theirs = np.abs(edited.speed[k][both]), np.abs(log.speed[j][both])
    if mine.size and (theirs[mine < STOP_SPEED] >= STOP_SPEED).any():
        return voc.STOPPED
    if mine.size and mine.mean() < theirs.mean() - PACE_DELTA:
        return "slowed"
    if mine.size and mine.mean() > theirs.mean() + PACE_DELTA:
        return "sped up"
    return "moved"


def _nearest(at: np.ndarray, step: int, edited: AgentStates, log: AgentStates, causes: list[str]) -> str:
    """The cause (object id) nearest to ``at`` (``[2]``) at ``step``, ``""`` when none exists then."""
    best, best_d = "", math.inf
    for oid in causes:
        states = edited if oid in edited.object_ids else log
        r = states.index(oid)
        if states.valid[r, step]:
            d = float(np.linalg.norm(states.xy[r, step] - at))
            if d < best_d:
                best, best_d = oid, d
    return best


def agent_changes(edited: AgentStates, log: AgentStates) -> list[AgentChange]:
    """Every agent of ``edited`` whose source is not ``"log"``, and every log agent the edit removed, as
    :class:`AgentChange` (module docstring): the edit's agents, then the removed, then the refined.

    Raises:
        ValueError: the two states are not on the same steps.
    """
    if edited.num_steps != log.num_steps:
        raise ValueError(f"agent_changes: {edited.num_steps} edited steps vs {log.num_steps} log steps")
    removed = [o for o in log.object_ids if o not in edited.object_ids]
    causes = [o for o, s in zip(edited.object_ids, edited.sources) if s in EDIT_SOURCES] + removed
    out: list[AgentChange] = []
    for k, (oid, category, source) in enumerate(zip(edited.object_ids, edited.categories, edited.sources)):
        if source == "log":
            continue
        mine = edited.valid[k]
        j = log.index(oid) if oid in log.object_ids else None
        if j is None:
            out.append(AgentChange(oid, category, source, math.nan, math.nan, _min_abs(edited.speed[k][mine]),
                                   math.nan))
            continue
        both = mine & log.valid[j]
        gaps = np.linalg.norm(edited.xy[k] - log.xy[j], axis=-1)  # [T]
        ours, theirs = edited.xy[k][mine], log.xy[j][log.valid[j]]  # [M, 2], [L, 2]
        offset = float(np.linalg.norm(ours[:, None] - theirs[None], axis=-1).min(axis=1).max()) \
            if ours.size and theirs.size else math.nan
        change = AgentChange(oid, category, source, float(gaps[both].max()) if both.any() else math.nan, offset,
                             _min_abs(edited.speed[k][mine]), _min_abs(log.speed[j][log.valid[j]]))
        moved = np.flatnonzero(both & (gaps > MOVED_M))
        if source == "refined" and moved.size:
            step = int(moved[0])
            change = dataclasses.replace(change, reaction=_reaction(edited, log, k, j, offset),
                                         reacts_to=_nearest(edited.xy[k, step], step, edited, log, causes),
                                         reaction_frame=int(edited.frame_idx[step]))
        out.append(change)
    for oid in removed:
        j = log.index(oid)
        out.append(AgentChange(oid, log.categories[j], REMOVED, math.nan, math.nan, math.nan,
                               _min_abs(log.speed[j][log.valid[j]])))
    rank = {"edited": 0, "inserted": 0, REMOVED: 1, "refined": 2}
    return sorted(out, key=lambda c: rank.get(c.source, 3))


__all__ = ["DETOUR_M", "EDIT_SOURCES", "MOVED_M", "PACE_DELTA", "REMOVED", "STOP_SPEED", "AgentChange",
           "agent_changes"]
