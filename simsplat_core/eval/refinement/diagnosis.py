"""Why a rollout under-drives: one row per agent that is stopped in the rollout where the log has it moving.

An agent *stalls* at a step when its rollout speed (from the box centres' displacement) is below
``STOP_SPEED_MPS`` while its logged speed is not; it is listed when it stalls for at least ``min_steps`` steps.
Its row names what held it back over those steps (``ReactivePredictor.traced_rollout``'s ``LimitTrace``): the
most frequent rule (``leader``, ``gap acceptance``, or ``free road`` where nothing in the way slowed it: its
speed profile did), the blocker (the other agent's id and kind, ``parked`` when that agent does not move in the
log, ``kerb obstacle`` for static objects) and the median distance to it.

    stalls = diagnose(scenario, rollout, trace)
    table = STALLS_SPEC.table([s.row() for s in stalls])
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import asdict, dataclass

import numpy as np
import pyarrow as pa

from simsplat_core.eval.table_spec import Column, TableSpec
from simsplat_core.motion.predictor import Rollout
from simsplat_core.motion.reactive import RULE_FREE, RULE_NAMES, LimitTrace
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.metrics import STATIC, kind_of
from simsplat_core.scenario.rollout_metrics import MIN_LOG_PATH_M, STOP_SPEED_MPS, STOP_STEPS

#: Blocker of a row held back by nothing in the way.
NO_BLOCKER = "none (speed profile)"


@dataclass(frozen=True)
class Stall:
    """One stalled agent (module docstring).

    Attributes:
        dataset, seq_id: the scenario; window: its first step in the source log (``0``: the whole log).
        object_id, kind: the stalled agent.
        steps: steps it stalls; first_step: the first of them.
        rule: what limited it most often over those steps.
        blocker: ``"<id> (<kind>)"``, ``"<id> (parked <kind>)"``, ``"<id> (kerb obstacle)"`` or :data:`NO_BLOCKER`.
        distance_m: median gap to the blocker over the stalled steps (NaN: none).
        progress: rollout path length over the log's from the first predicted step.
    """

    dataset: str
    seq_id: str
    window: int
    object_id: str
    kind: str
    steps: int
    first_step: int
    rule: str
    blocker: str
    distance_m: float
    progress: float

    def row(self) -> dict[str, object]:
        """The row of :data:`STALLS_SPEC`."""
        return asdict(self)


#: ``tables/motion_stalls``: one row per agent stopped in a rollout but moving in the log.
STALLS_SPEC = TableSpec(
    "motion_stalls", "Motion: agents stopped in the rollout but moving in the log", "(scenario, window, agent)", (
        Column("dataset", pa.string(), "the real dataset"), Column("seq_id", pa.string(), "the log"),
        Column("window", pa.int64(), "the window's first step in the log", "step"),
        Column("object_id", pa.string(), "the stalled agent"), Column("kind", pa.string(), "its kind"),
        Column("steps", pa.int64(), "steps stopped while moving in the log", "count"),
        Column("first_step", pa.int64(), "the first of them", "step"),
        Column("rule", pa.string(), "what stopped it: leader | gap acceptance | free road"),
        Column("blocker", pa.string(), "the agent in the way (id and kind) or none"),
        Column("distance_m", pa.float64(), "median gap to the blocker (NaN: none)", "m"),
        Column("progress", pa.float64(), "rollout path over log path", "share")),
    keys=("dataset", "seq_id", "window", "object_id"), digits=2, detail=True)


def _speeds(states: AgentStates) -> np.ndarray:
    """``[A, T]`` speed from the box centres' displacement (step ``t`` from ``t - 1``; 0 at step 0 and where
    either step is invalid)."""
    dt = np.maximum(np.diff(states.times), 1e-9)
    v = np.linalg.norm(np.diff(states.xy, axis=1), axis=-1) / dt
    v = np.where(states.valid[:, 1:] & states.valid[:, :-1], v, 0.0)
    return np.concatenate([np.zeros((states.num_agents, 1)), v], axis=1)


def _path(xy: np.ndarray, valid: np.ndarray) -> float:
    step = np.linalg.norm(np.diff(xy, axis=0), axis=-1)
    return float(step[valid[1:] & valid[:-1]].sum())


def blocker_name(log: AgentStates, row: int, start_step: int) -> str:
    """``"<id> (<kind>)"`` of agent ``row``, ``parked`` when it moves less than ``MIN_LOG_PATH_M`` in the log from
    ``start_step`` on, ``kerb obstacle`` for a static object."""
    kind = kind_of(log.categories[row])
    oid = log.object_ids[row]
    if kind == STATIC:
        return f"{oid} (kerb obstacle)"
    parked = _path(log.xy[row, start_step:], log.valid[row, start_step:]) < MIN_LOG_PATH_M
    return f"{oid} (parked {kind})" if parked else f"{oid} ({kind})"


def diagnose(log: AgentStates, rollout: Rollout, trace: LimitTrace, start_step: int, *, dataset: str = "",
             seq_id: str = "", window: int = 0, min_steps: int = STOP_STEPS) -> list[Stall]:
    """The stalled agents of ``rollout`` (module docstring), longest stall first.

    Args:
        log: the logged states (the request's); rollout: the predictor's answer with ``trace`` its limits.
        start_step: the first predicted step; min_steps: fewest stalled steps listed.
    """
    got = rollout.states
    v_log, v_roll = _speeds(log), _speeds(got)
    stalls: list[Stall] = []
    for k, row in enumerate(trace.rows.tolist()):
        both = log.valid[row] & got.valid[row]
        both[:start_step] = False
        stalled = both & (v_roll[row] < STOP_SPEED_MPS) & (v_log[row] >= STOP_SPEED_MPS)
        steps = np.flatnonzero(stalled)
        if steps.size < min_steps:
            continue
        rules = Counter(trace.rule[k, steps].tolist())
        rule = max(rules, key=lambda r: (rules[r], r != RULE_FREE))
        at = steps[trace.rule[k, steps] == rule]
        others = Counter(int(o) for o in trace.other[k, at] if o >= 0)
        blocker = blocker_name(log, others.most_common(1)[0][0], start_step) if others else NO_BLOCKER
        gaps = trace.gap[k, at]
        gaps = gaps[np.isfinite(gaps)]
        span = both.copy()
        span[start_step - 1] = log.valid[row, start_step - 1] and got.valid[row, start_step - 1]
        log_len, roll_len = _path(log.xy[row], span), _path(got.xy[row], span)
        stalls.append(Stall(dataset=dataset, seq_id=seq_id, window=window, object_id=log.object_ids[row],
                            kind=kind_of(log.categories[row]), steps=int(steps.size), first_step=int(steps[0]),
                            rule=RULE_NAMES[rule], blocker=blocker,
                            distance_m=float(np.median(gaps)) if gaps.size else math.nan,
                            progress=roll_len / log_len if log_len > 0 else math.nan))
    return sorted(stalls, key=lambda s: -s.steps)


def stalls_table(stalls: list[Stall]) -> pa.Table:
    """:data:`STALLS_SPEC`'s table of ``stalls``."""
    return STALLS_SPEC.table([s.row() for s in stalls])


__all__ = ["NO_BLOCKER", "STALLS_SPEC", "Stall", "blocker_name", "diagnose", "stalls_table"]
