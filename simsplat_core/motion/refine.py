"""Refinement of an edited scenario: the traffic around an edit reacts to it.

    refined = refine(edited_states, motion_map, ReactivePredictor(), mode="full")
    refined.states        # AgentStates; reacting agents carry source "refined"
    refined.replayed      # agents the predictor could not drive, with the reason

Three modes, the rows of the ``motion`` table (a SIMSplat Table 4 analogue):

* ``"none"``: nothing is refined; every agent but the edited ones replays its log (deterministic editing);
* ``"single-agent"``: only the edited and inserted agents are driven by the predictor (their edited
  trajectory is their intent: route and desired speed), so they avoid conflicts; everyone else replays;
* ``"full"``: the edited and inserted agents keep the trajectory the edit gave them, and every other free
  agent is driven by the predictor so it reacts (follows, yields, waits, detours).

In ``"full"`` mode only the agents the edit affects change: the predictor also rolls the unedited scenario out,
and an agent whose rollout with the edit stays within :data:`AFFECTED_M` of its rollout without it keeps its
log exactly (the predictor's own error against the log is not passed off as a reaction to the edit), unless its
log runs into an agent the edit added, changed or made react, or into one that keeps its rollout for this very
reason (then it keeps its rollout too; repeated until no log runs into a rollout). An agent that appears only
after the start step has no state to predict from there; when its log runs into an agent the edit changed or
made react, it is driven from the step after it appears (a second rollout that keeps everyone else as they are),
so a car that enters the scene behind a braking one slows down too (:func:`_drive_late_arrivals`).

The ego is fixed by default: its cameras render the scene, and a render is only as good as the views the scene
was reconstructed from. With ``ego_reacts=True`` the ego is driven like any other free agent of the mode (for
logs nothing is rendered from, e.g. real motion datasets without camera images). Static objects are always
fixed. Prediction starts at ``start_step``: by default the
first step where an edited or inserted agent differs from the log (at least 1), since an edit present from
the first frame must be reacted to from the first frame.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from simsplat_core.motion.predictor import MotionMap, MotionPredictor, RolloutRequest
from simsplat_core.motion.routes import APPEARS_LATER
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.metrics import collision_steps
from simsplat_core.scenario.trajectory import agent_kind

logger = logging.getLogger(__name__)

RefineMode = Literal["none", "single-agent", "full"]
#: Refinement modes, in the evaluation table's order.
REFINE_MODES: tuple[str, ...] = get_args(RefineMode)
#: Sources of the agents an edit changed.
EDIT_SOURCES: frozenset[str] = frozenset({"edited", "inserted"})
#: An edited agent differs from its log where their box centres are further apart than this, metres.
DIVERGENCE_M = 0.05
#: An agent reacts to the edit when its rollout with the edit leaves its rollout without it by more than this, m.
AFFECTED_M = 0.3


@dataclass(frozen=True)
class Refinement:
    """A refined scenario.

    Attributes:
        states: every agent over the same steps; agents the predictor moved carry ``source == "refined"``
            (edited and inserted agents keep their source).
        mode: the refinement mode.
        start_step: first predicted step (history before it).
        replayed: ``object_id -> reason`` for agents the predictor should have driven but replayed.
        predictor: name of the predictor (``""`` for mode ``"none"``).
    """

    states: AgentStates
    mode: str
    start_step: int
    replayed: dict[str, str]
    predictor: str

    @property
    def refined_ids(self) -> tuple[str, ...]:
        """Ids of the agents whose path the predictor changed."""
        return tuple(o for o, s in zip(self.states.object_ids, self.states.sources) if s == "refined")


def edit_start_step(states: AgentStates, original: AgentStates | None = None) -> int:
    """First step at which an edited / inserted agent exists and differs from its log (at least 1).

    Args:
        states: the edited scenario; original: the log (``None``: every edited agent counts as differing
            wherever it is valid).
    """
    first = states.num_steps - 1
    for r, (oid, source) in enumerate(zip(states.object_ids, states.sources)):
        if source not in EDIT_SOURCES:
            continue
        differs = states.valid[r].copy()
        if original is not None and oid in original.object_ids:
            k = original.index(oid)
            gap = np.linalg.norm(states.xy[r] - original.xy[k], axis=-1)
            differs &= ~original.valid[k] | (gap > DIVERGENCE_M)
        if differs.any():
            first = min(first, int(np.argmax(differs)))
    return int(np.clip(first, 1, max(states.num_steps - 1, 1)))


def fixed_rows(states: AgentStates, mode: str, *, ego_reacts: bool = False) -> np.ndarray:
    """``[F]`` rows the predictor must not move in ``mode`` (see the module docstring).

    Args:
        ego_reacts: the ego is free like the other unedited agents (mode ``"full"`` drives it); default
            fixed, since a rendered edit needs the log's camera poses.
    """
    if mode not in REFINE_MODES:
        raise ValueError(f"refinement mode must be one of {list(REFINE_MODES)}, got {mode!r}")
    fixed = []
    for r, (oid, category, source) in enumerate(zip(states.object_ids, states.categories, states.sources)):
        movable = (ego_reacts or oid != EGO_ID) and agent_kind(category) is not None
        edited = source in EDIT_SOURCES
        free = movable and (edited if mode == "single-agent" else (not edited and mode == "full"))
        if not free:
            fixed.append(r)
    return np.asarray(fixed, dtype=np.int64)


def _only_affected(out: AgentStates, states: AgentStates, original: AgentStates, predictor: MotionPredictor,
                   motion_map: MotionMap, start: int, fixed: np.ndarray) -> AgentStates:
    """``out`` with every free agent the edit does not affect restored to its log (module docstring).

    The unedited rollout keeps fixed what the edited one keeps fixed (by id), and the agents the edit removed.
    """
    fixed_ids = {states.object_ids[int(r)] for r in fixed}
    base_fixed = [k for k, oid in enumerate(original.object_ids) if oid in fixed_ids or oid not in states.object_ids]
    base = predictor.rollout(RolloutRequest(original, start, np.asarray(base_fixed, dtype=np.int64),
                                            motion_map)).states
    unaffected = []
    for r, oid in enumerate(out.object_ids):
        if oid in fixed_ids or oid not in original.object_ids:
            continue
        k = original.index(oid)
        both = out.valid[r, start:] & base.valid[k, start:]
        gap = np.linalg.norm(out.xy[r, start:] - base.xy[k, start:], axis=-1)[both]
        same_presence = np.array_equal(out.valid[r, start:], base.valid[k, start:])
        if same_presence and float(gap.max(initial=0.0)) <= AFFECTED_M:
            unaffected.append(r)
    # an agent the predictor drives the same with and without the edit may still need its rollout: its log runs
    # into the edit (the predictor already held it back for something else, where the log did not stop), or into
    # an agent that needs its rollout for that reason (a car merging behind one that now keeps its rollout)
    keep_log = unaffected
    while True:
        restored = _restored(out, states, keep_log)
        if not keep_log:
            return restored
        hits = np.asarray(collision_steps(restored, keep_log).pairs[:, :, start:].any(axis=(1, 2)), dtype=bool)
        if not hits.any():
            return restored
        keep_log = [r for r, hit in zip(keep_log, hits.tolist()) if not hit]


def _restored(out: AgentStates, states: AgentStates, rows: list[int]) -> AgentStates:
    """``out`` with ``rows`` taken from ``states`` (trajectory, validity and source)."""
    xy, heading, speed = out.xy.copy(), out.heading.copy(), out.speed.copy()
    valid, z, sources = out.valid.copy(), out.z.copy(), list(out.sources)
    for r in rows:
        xy[r], heading[r], speed[r] = states.xy[r], states.heading[r], states.speed[r]
        valid[r], z[r], sources[r] = states.valid[r], states.z[r], states.sources[r]
    return dataclasses.replace(out, xy=xy, heading=heading, speed=speed, valid=valid, z=z, sources=tuple(sources))


def _drive_late_arrivals(out: AgentStates, replayed: dict[str, str], predictor: MotionPredictor,
                         motion_map: MotionMap) -> tuple[AgentStates, dict[str, str]]:
    """``out`` with each agent that appeared after the start step (replayed from its log) and whose log runs into
    a changed agent driven from the step after it appears, earliest arrival first (module docstring); the
    agents still replayed, with their reasons."""
    replayed = dict(replayed)
    late = [out.index(o) for o, why in replayed.items() if why == APPEARS_LATER]
    changed = [r for r, src in enumerate(out.sources) if src != "log"]
    if not late or not changed:
        return out, replayed
    for row in sorted(late, key=lambda r: int(np.argmax(out.valid[r]))):
        first = int(np.argmax(out.valid[row]))
        if first + 1 >= out.num_steps:
            continue
        hits = collision_steps(out, [row]).pairs[0][changed][:, first:]
        if not hits.any():
            continue
        fixed = np.asarray([r for r in range(out.num_agents) if r != row], dtype=np.int64)
        rolled = predictor.rollout(RolloutRequest(out, first + 1, fixed, motion_map))
        if out.object_ids[row] in rolled.replayed:
            replayed[out.object_ids[row]] = rolled.replayed[out.object_ids[row]]
            continue
        out = _restored(out, rolled.states, [row])
        del replayed[out.object_ids[row]]
        changed.append(row)
    return out, replayed


def refine(states: AgentStates, motion_map: MotionMap, predictor: MotionPredictor | None, mode: str = "full",
           *, original: AgentStates | None = None, start_step: int | None = None,
           ego_reacts: bool = False) -> Refinement:
    """The scenario ``states`` with its free agents re-driven by ``predictor`` (module docstring).

    Args:
        states: the edited scenario (edited / inserted agents marked by their ``source``).
        motion_map: the map to drive on.
        predictor: the motion predictor (unused, may be ``None``, for mode ``"none"``).
        mode: one of :data:`REFINE_MODES`.
        original: the unedited scenario (to find where the edit starts; see :func:`edit_start_step`).
        start_step: first predicted step (default: :func:`edit_start_step`).
        ego_reacts: let the ego react too (see :func:`fixed_rows`; only for scenarios nothing is rendered from).

    Raises:
        ValueError: unknown mode, or no predictor for a mode that needs one.
    """
    rows = fixed_rows(states, mode, ego_reacts=ego_reacts)
    start = edit_start_step(states, original) if start_step is None else int(start_step)
    if mode == "none" or len(rows) == states.num_agents:
        return Refinement(states, mode, start, {}, "")
    if predictor is None:
        raise ValueError(f"refinement mode {mode!r} needs a motion predictor")
    rollout = predictor.rollout(RolloutRequest(states, start, rows, motion_map))
    out = rollout.states
    replayed = dict(rollout.replayed)
    if mode == "full" and original is not None:
        out = _only_affected(out, states, original, predictor, motion_map, start, rows)
        out, replayed = _drive_late_arrivals(out, replayed, predictor, motion_map)
    if mode == "single-agent":  # the edited agents keep their source: the predictor only adjusted them
        sources = tuple(s if s != "refined" or states.sources[r] not in EDIT_SOURCES else states.sources[r]
                        for r, s in enumerate(out.sources))
        out = dataclasses.replace(out, sources=sources)
    if replayed:
        logger.info("refinement (%s): %d agent(s) replay their log: %s", mode, len(replayed),
                    "; ".join(f"{k}: {v}" for k, v in sorted(replayed.items())))
    refined = Refinement(out, mode, start, replayed, rollout.predictor)
    logger.info("refinement (%s, %s) from step %d: %d agent(s) reacted", mode, rollout.predictor, start,
                len(refined.refined_ids))
    return refined
