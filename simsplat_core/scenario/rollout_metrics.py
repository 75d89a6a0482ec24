"""Metrics of a rollout of every agent against the logged future (the failure rates of the ``motion`` table).

The rollout starts from the log's first steps (``start_step`` is the last logged step it was given) and
predicts every agent after it; both are :class:`~simsplat_core.scenario.agents.AgentStates` on the same
steps, agents matched by ``object_id``.

* :func:`displacement_errors` -- Waymo motion's ADE / FDE per agent and per agent type: ADE at horizon
  ``h`` is the mean L2 distance between the rollout's and the log's box centres over the future steps
  ``start_step + 1 .. start_step + H`` (``H`` = ``h`` in steps) where both are valid; FDE is the L2 distance
  at step ``start_step + H`` (NaN where either is invalid there). Beyond the data both are NaN.
* :func:`scenario_failures` -- whether any agent collides (with a vehicle / a pedestrian / a static
  object), leaves the road or moves infeasibly, with the checks of ``scenario.metrics``; run on the log
  itself it gives the log's own rates to set next to the rollout's.
* :func:`progress_and_stops` -- path length travelled in the rollout relative to the log, and the share of
  moving agents that the rollout leaves stopped for good.
* :func:`rates` -- the share of scenarios with each failure, for the evaluation table.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import collision_steps, kind_of, kinematic_violations, offroad_steps

logger = logging.getLogger(__name__)

#: Horizons of :func:`displacement_errors`, seconds (Waymo motion reports 3, 5 and 8 s).
DEFAULT_HORIZONS_S: tuple[float, ...] = (3.0, 8.0)
#: Agent type of cyclists in the ADE / FDE breakdown (``kind_of`` counts them as vehicles).
CYCLIST = "cyclist"
#: An agent must travel at least this far in the log (after ``start_step``) to count in progress and stops.
MIN_LOG_PATH_M = 2.0
#: Bounds of one agent's progress ratio (an agent driving off far beyond its route does not dominate the mean).
PROGRESS_CLIP: tuple[float, float] = (0.0, 2.0)
#: Below this speed (m/s, from the box centres' displacement) an agent is stopped.
STOP_SPEED_MPS = 0.5
#: An agent is stopped for good when it is stopped over this many last steps of the rollout.
STOP_STEPS = 10
#: Steps over which a stopped agent's speed is measured (box jitter averages out).
STOP_BASELINE_STEPS = 5
#: Columns of :func:`rates` (the ``motion`` table's failure rates), in table order.
FAILURE_COLUMNS: tuple[str, ...] = ("collision_vehicle", "collision_pedestrian", "offroad", "kinematic", "failure")


def _check_same_steps(rollout: AgentStates, log: AgentStates, start_step: int) -> None:
    if rollout.num_steps != log.num_steps or not np.allclose(rollout.times, log.times):
        raise ValueError(f"rollout and log must share their steps: {rollout.num_steps} vs {log.num_steps} steps "
                         "or different times")
    if not 0 <= start_step < log.num_steps:
        raise IndexError(f"start_step {start_step} out of range for {log.num_steps} steps")


def _matched_rows(rollout: AgentStates, log: AgentStates) -> tuple[np.ndarray, np.ndarray]:
    """``([M], [M])`` rows of the agents present in both (by ``object_id``), in the log's order."""
    index = {oid: k for k, oid in enumerate(rollout.object_ids)}
    pairs = [(index[oid], k) for k, oid in enumerate(log.object_ids) if oid in index]
    roll = np.array([p[0] for p in pairs], dtype=np.int64)
    base = np.array([p[1] for p in pairs], dtype=np.int64)
    return roll, base


def agent_type(category: str) -> str:
    """Type of an agent in the ADE / FDE breakdown: ``"cyclist"``, else :func:`~.metrics.kind_of`."""
    return CYCLIST if category == CYCLIST else kind_of(category)


def horizon_steps(times: np.ndarray, horizon_s: float) -> int:
    """Number of steps ``[T]`` times spaced by their median step cover ``horizon_s`` (at least 1)."""
    if len(times) < 2:
        raise ValueError("need at least two steps to turn a horizon in seconds into steps")
    dt = float(np.median(np.diff(times)))
    return max(1, int(round(horizon_s / dt)))


def _mean(values: np.ndarray) -> float:
    """Mean of the finite entries of ``values``, NaN when there are none (no warning)."""
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else math.nan


def _null(value: float) -> float | None:
    return None if math.isnan(value) else value


@dataclass(frozen=True)
class DisplacementErrors:
    """ADE / FDE of ``M`` matched agents at ``H`` horizons.

    Attributes:
        horizons_s: ``[H]`` horizons, seconds.
        horizon_steps: ``[H]`` the horizons in steps.
        object_ids: ``[M]`` agents present in both the rollout and the log.
        types: ``[M]`` ``"vehicle"``, ``"pedestrian"``, ``"cyclist"`` or ``"static"`` (:func:`agent_type`).
        ade: ``[M, H]`` float64 metres, NaN where no future step within the horizon has both valid or the
            horizon runs beyond the data.
        fde: ``[M, H]`` float64 metres, NaN where either is invalid at the horizon step or it is beyond the data.
    """

    horizons_s: tuple[float, ...]
    horizon_steps: tuple[int, ...]
    object_ids: tuple[str, ...]
    types: tuple[str, ...]
    ade: np.ndarray
    fde: np.ndarray

    def _column(self, horizon_s: float) -> int:
        for h, value in enumerate(self.horizons_s):
            if math.isclose(value, horizon_s):
                return h
        raise KeyError(f"no horizon {horizon_s} s (have {list(self.horizons_s)})")

    def mean(self, horizon_s: float, of_type: str | None = None) -> tuple[float, float]:
        """``(ADE, FDE)`` means over the agents (of type ``of_type``, default all) where defined, else NaN."""
        h = self._column(horizon_s)
        pick = np.array([of_type is None or t == of_type for t in self.types], dtype=bool)
        return _mean(self.ade[pick, h]), _mean(self.fde[pick, h])

    def by_type(self) -> dict[str, dict[str, float]]:
        """Per agent type present, ``{"ade_3s": ..., "fde_3s": ..., ...}`` means (NaN where undefined)."""
        out: dict[str, dict[str, float]] = {}
        for kind in sorted(set(self.types)):
            row: dict[str, float] = {}
            for horizon in self.horizons_s:
                row[f"ade_{horizon:g}s"], row[f"fde_{horizon:g}s"] = self.mean(horizon, kind)
            out[kind] = row
        return out

    def as_row(self) -> dict[str, float | None]:
        """Table columns ``ade_<h>s`` / ``fde_<h>s`` over all agents, ``None`` where undefined."""
        row: dict[str, float | None] = {}
        for horizon in self.horizons_s:
            ade, fde = self.mean(horizon)
            row[f"ade_{horizon:g}s"], row[f"fde_{horizon:g}s"] = _null(ade), _null(fde)
        return row


def displacement_errors(rollout: AgentStates, log: AgentStates, start_step: int,
                        horizons_s: Sequence[float] = DEFAULT_HORIZONS_S) -> DisplacementErrors:
    """ADE / FDE of every agent present in both ``rollout`` and ``log`` (see the module docstring).

    Args:
        rollout, log: the same ``T`` steps; agents matched by ``object_id``.
        start_step: index of the last given step; the future is ``start_step + 1 ..``.
        horizons_s: horizons in seconds, turned into steps with the states' median time step.
    """
    _check_same_steps(rollout, log, start_step)
    roll, base = _matched_rows(rollout, log)
    steps = tuple(horizon_steps(log.times, h) for h in horizons_s)
    both = rollout.valid[roll] & log.valid[base]  # [M, T]
    dist = np.linalg.norm(rollout.xy[roll] - log.xy[base], axis=-1)  # [M, T]
    ade = np.full((len(base), len(steps)), np.nan)
    fde = np.full((len(base), len(steps)), np.nan)
    for h, n in enumerate(steps):
        end = start_step + n
        if end >= log.num_steps:
            logger.debug("horizon %.3g s ends at step %d beyond the %d steps: ADE/FDE undefined",
                         horizons_s[h], end, log.num_steps)
            continue
        window = slice(start_step + 1, end + 1)
        count = both[:, window].sum(axis=1)
        total = np.where(both[:, window], dist[:, window], 0.0).sum(axis=1)
        ade[:, h] = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        fde[:, h] = np.where(both[:, end], dist[:, end], np.nan)
    return DisplacementErrors(horizons_s=tuple(float(h) for h in horizons_s), horizon_steps=steps,
                              object_ids=tuple(log.object_ids[k] for k in base),
                              types=tuple(agent_type(log.categories[k]) for k in base), ade=ade, fde=fde)


# --------------------------------------------------------------------------------------------- failures
@dataclass(frozen=True)
class ScenarioFailures:
    """Failures of one scenario (any checked agent, any step).

    Attributes:
        collision_vehicle / collision_pedestrian / collision_static: some agent's box overlaps a vehicle
            (the ego included) / a pedestrian / a static object's.
        offroad: some agent leaves the drivable (walkable) area.
        kinematic: some agent's motion exceeds its kind's kinematic bounds.
        failed_agents: ids of the agents with any failure, in row order.
    """

    collision_vehicle: bool = False
    collision_pedestrian: bool = False
    collision_static: bool = False
    offroad: bool = False
    kinematic: bool = False
    failed_agents: tuple[str, ...] = ()

    @property
    def failure(self) -> bool:
        """Any collision (static objects included), off-road or kinematic failure."""
        return (self.collision_vehicle or self.collision_pedestrian or self.collision_static or self.offroad
                or self.kinematic)

    def as_dict(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self.__dataclass_fields__} | {"failure": self.failure}


def scenario_failures(states: AgentStates, map_ctx: MapContext, rows: Sequence[int] | np.ndarray | None = None,
                      baseline: AgentStates | None = None) -> ScenarioFailures:
    """Collisions, off-road and kinematic failures of ``rows`` (default: every agent) against every agent.

    Unlike edit validation, pairs of two log agents count: in a rollout every agent moves, and the log's own
    rate is measured the same way. Given ``baseline`` (the log on the same steps), a pair that overlapped
    there at the same step is the log's overlap and does not count (``metrics.collision_steps``), and an agent
    that drives exactly its baseline trajectory (:func:`unchanged_rows`) has no off-road or kinematic failure
    of its own: a car parked half off the road in the log is not the edit's failure.
    """
    rows = np.arange(states.num_agents) if rows is None else np.asarray(rows, dtype=np.int64).reshape(-1)
    coll = collision_steps(states, rows, baseline, count_log_pairs=True)
    own = ~unchanged_rows(states, rows, baseline)  # [R]
    off = offroad_steps(states, map_ctx, rows).any(axis=1) & own  # [R]
    kin = kinematic_violations(states, rows=rows).any(axis=1) & own  # [R]
    veh, ped, sta = coll.vehicle.any(axis=1), coll.pedestrian.any(axis=1), coll.static.any(axis=1)  # [R]
    failed = veh | ped | sta | off | kin
    return ScenarioFailures(collision_vehicle=bool(veh.any()), collision_pedestrian=bool(ped.any()),
                            collision_static=bool(sta.any()), offroad=bool(off.any()), kinematic=bool(kin.any()),
                            failed_agents=tuple(states.object_ids[int(r)] for r in rows[failed]))


def unchanged_rows(states: AgentStates, rows: Sequence[int] | np.ndarray, baseline: AgentStates | None
                   ) -> np.ndarray:
    """``[R]`` bool: agent ``rows`` of ``states`` exist in ``baseline`` (by id) with the same validity and box
    centres (within 1 mm) at every step; all ``False`` without a baseline."""
    rows = np.asarray(rows, dtype=np.int64).reshape(-1)
    out = np.zeros(len(rows), dtype=bool)
    if baseline is None:
        return out
    for k, r in enumerate(rows):
        oid = states.object_ids[int(r)]
        if oid not in baseline.object_ids:
            continue
        b = baseline.index(oid)
        valid = states.valid[r]
        out[k] = bool(np.array_equal(valid, baseline.valid[b])
                      and np.abs(states.xy[r, valid] - baseline.xy[b, valid]).max(initial=0.0) <= 1e-3)
    return out


def rates(failures: Sequence[ScenarioFailures]) -> dict[str, float]:
    """Share of ``failures`` (one per scenario) with each of :data:`FAILURE_COLUMNS`, in ``[0, 1]``."""
    if not failures:
        raise ValueError("rates of no scenarios are undefined")
    return {col: float(np.mean([bool(getattr(f, col)) for f in failures])) for col in FAILURE_COLUMNS}


# --------------------------------------------------------------------------------------------- progress
@dataclass(frozen=True)
class Progress:
    """Progress of the rollout along the logged routes.

    Attributes:
        progress: mean over the agents that moved in the log of their clipped progress ratio (NaN if none).
        stopped_share: share of those agents that end the rollout stopped for good (NaN if none).
        object_ids: ``[N]`` the agents that moved in the log.
        ratios: ``[N]`` float64 rollout path length / log path length, clipped to :data:`PROGRESS_CLIP`.
        stopped: ``[N]`` bool, stopped over the last :data:`STOP_STEPS` steps of the rollout.
    """

    progress: float
    stopped_share: float
    object_ids: tuple[str, ...]
    ratios: np.ndarray
    stopped: np.ndarray

    def as_row(self) -> dict[str, float | None]:
        """Table columns ``progress`` and ``stopped_share``, ``None`` where undefined."""
        return {"progress": _null(self.progress), "stopped_share": _null(self.stopped_share)}


def _path_lengths(xy: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """``[N]`` summed step lengths of ``xy [N, T, 2]`` over segments with both ends ``valid [N, T]``."""
    seg = np.linalg.norm(np.diff(xy, axis=1), axis=-1)  # [N, T-1]
    return np.where(valid[:, 1:] & valid[:, :-1], seg, 0.0).sum(axis=1)


def _stopped_at_end(states: AgentStates, rows: np.ndarray) -> np.ndarray:
    """``[N]`` bool: valid over the last ``STOP_STEPS + STOP_BASELINE_STEPS`` steps and slower than
    ``STOP_SPEED_MPS`` on each of the last ``STOP_STEPS``, the speed measured by the box centre's displacement
    over ``STOP_BASELINE_STEPS`` steps (a stopped box that jitters by a few centimetres a step is stopped, an
    agent walking slowly is not, whether in the log or a rollout)."""
    k = STOP_BASELINE_STEPS
    if states.num_steps < STOP_STEPS + k:
        return np.zeros(len(rows), dtype=bool)
    tail = slice(states.num_steps - STOP_STEPS - k, states.num_steps)
    xy, valid, times = states.xy[rows, tail], states.valid[rows, tail], states.times[tail]  # [N, S+k, 2], [N, S+k]
    dt = np.maximum(times[k:] - times[:-k], 1e-9)  # [S]
    speed = np.linalg.norm(xy[:, k:] - xy[:, :-k], axis=-1) / dt  # [N, S]
    return valid.all(axis=1) & (speed < STOP_SPEED_MPS).all(axis=1)


def progress_and_stops(rollout: AgentStates, log: AgentStates, start_step: int) -> Progress:
    """Progress ratios and stops of the agents that travel at least :data:`MIN_LOG_PATH_M` in the log.

    Path lengths are summed over the steps from ``start_step`` on where both the rollout and the log have
    the agent (so a track that ends in the log is compared over the same span).
    """
    _check_same_steps(rollout, log, start_step)
    roll, base = _matched_rows(rollout, log)
    future = slice(start_step, log.num_steps)
    both = rollout.valid[roll, future] & log.valid[base, future]  # [M, T']
    log_len = _path_lengths(log.xy[base, future], both)
    roll_len = _path_lengths(rollout.xy[roll, future], both)
    moved = log_len >= MIN_LOG_PATH_M
    ratios = np.clip(roll_len[moved] / np.maximum(log_len[moved], MIN_LOG_PATH_M), *PROGRESS_CLIP)
    stopped = _stopped_at_end(rollout, roll[moved])
    logger.debug("progress over %d of %d matched agents that moved in the log", int(moved.sum()), len(base))
    return Progress(progress=_mean(ratios), stopped_share=float(stopped.mean()) if stopped.size else math.nan,
                    object_ids=tuple(log.object_ids[int(k)] for k in base[moved]), ratios=ratios, stopped=stopped)
