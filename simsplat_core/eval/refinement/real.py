"""Rollouts on real driving logs, scored against the logged future (the real-data rows of the ``motion`` table).

One :class:`RealScenario` per log: every agent (the ego included) on a 10 Hz grid
(``AgentStates.from_log``, resampled when the source is not 10 Hz), its :class:`MotionMap` and the first
predicted step (default :data:`START_STEP` = 11: 1.1 s of history, Waymo Open Motion's ``current_time_index``
10 is the last observed step). The ego is fixed (it replays its log: its cameras recorded the scene), every
other agent is free. Logs shorter than ``START_STEP + 2`` steps are refused (named); a log too short for a
horizon has that horizon's ADE undefined (``None``), never an error.

Scores of one rollout (:func:`score_rollout`), all over the whole horizon (history included, the same for
every method) and over every agent:

* the failures of ``scenario.rollout_metrics.scenario_failures`` (a scenario fails when any agent fails);
  rollouts and the log itself are checked the same way, without a baseline (every overlap counts, the labels'
  own included) and on the same steps, those the log observed each agent at (as Waymo's sim-agents metrics
  take validity from the log), so that "a rollout's rate is at most twice the log's" compares like with like;
* per agent: the share of agents that collide with anyone (``agent_collision``) / leave the road at some
  step (``agent_offroad``), since one scenario's rates are 0 or 1;
* ADE / FDE at 3 s and 8 s (``displacement_errors`` from the last history step), per agent type too, and
  progress and stopped share (``progress_and_stops``), both over the agents observed at the last history
  step (agents that appear later are replayed by every predictor).

Rows (:func:`real_rows`) aggregate scenarios of one dataset, method and predictor: rates over scenarios,
per-agent shares, ADE and progress over the agents of all scenarios (pooled). A rollout's ``method`` is
:data:`ROLLOUT_METHOD` (``"full"``: every agent but the ego predicted) with ``predictor`` the predictor's name;
the log's row has ``method`` :data:`LOG_METHOD` and no predictor.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from simsplat_core.eval.refinement.diagnosis import Stall, diagnose
from simsplat_core.eval.refinement.scoring import score_agents
from simsplat_core.motion.motion_map import motion_map_of
from simsplat_core.motion.predictor import MotionMap, MotionPredictor, Rollout, RolloutRequest
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.rollout_metrics import (
    DisplacementErrors,
    Progress,
    ScenarioFailures,
    displacement_errors,
    progress_and_stops,
    rates,
    scenario_failures,
)
from simsplat_core.scenario.trajectory import resample_series
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: First predicted step (1.1 s of history at 10 Hz, as in Waymo Open Motion).
START_STEP = 11
#: Step rate of the evaluation, Hz.
STEP_HZ = 10.0
#: A source whose median step is within this relative tolerance of ``1 / STEP_HZ`` is used as it is.
RATE_TOLERANCE = 0.05
#: ADE horizons of the table, seconds.
HORIZONS_S: tuple[float, ...] = (3.0, 8.0)
#: Name of the log row's method.
LOG_METHOD = "log"
#: ``method`` of a rollout's row: every agent but the ego is predicted (refinement mode ``"full"``).
ROLLOUT_METHOD = "full"
#: ``dataset`` of a log by its ``SceneLog.source``.
DATASETS: dict[str, str] = {"waymo-scenario": "waymo-motion", "av2": "av2"}


# ------------------------------------------------------------------------------------------ resampling
def resample_states(states: AgentStates, hz: float = STEP_HZ) -> AgentStates:
    """``states`` on a regular ``hz`` grid from its first to its last time.

    Positions, heights and speeds are interpolated linearly, headings on their unwrapped values; an agent is
    valid at a grid time when both bracketing source steps are valid (or one of them coincides). ``frame_idx``
    is the nearest source frame.
    """
    t_src = states.times
    n = int(math.floor((t_src[-1] - t_src[0]) * hz + 1e-6)) + 1
    t_new = t_src[0] + np.arange(n) / hz
    hi = np.clip(np.searchsorted(t_src, t_new, side="left"), 0, len(t_src) - 1)
    lo = np.clip(hi - 1, 0, len(t_src) - 1)
    exact = np.isclose(t_src[hi], t_new, atol=1e-6)
    nearest = np.where(np.abs(t_src[lo] - t_new) <= np.abs(t_src[hi] - t_new), lo, hi)
    a = states.num_agents
    xy = np.zeros((a, n, 2))
    z, heading, speed = np.zeros((a, n)), np.zeros((a, n)), np.zeros((a, n))
    valid = np.where(exact[None], states.valid[:, hi], states.valid[:, lo] & states.valid[:, hi])
    for r in range(a):
        steps = np.flatnonzero(states.valid[r])
        if steps.size == 0:
            continue
        t = t_src[steps]
        values = np.column_stack([states.xy[r, steps], states.z[r, steps], np.unwrap(states.heading[r, steps]),
                                  states.speed[r, steps]])
        out = resample_series(t, values, t_new) if steps.size > 1 else np.repeat(values, n, axis=0)
        xy[r], z[r], heading[r], speed[r] = out[:, :2], out[:, 2], out[:, 3], out[:, 4]
    return replace(states, frame_idx=states.frame_idx[nearest], times=t_new, xy=xy, z=z, heading=heading,
                   speed=speed, valid=valid)


def on_step_grid(states: AgentStates, hz: float = STEP_HZ) -> tuple[AgentStates, bool]:
    """``(states at hz, resampled?)``: unchanged when the median step is within :data:`RATE_TOLERANCE`."""
    if states.num_steps < 2:
        return states, False
    dt = float(np.median(np.diff(states.times)))
    if abs(dt * hz - 1.0) <= RATE_TOLERANCE:
        return states, False
    logger.info("resampling %d steps of %.4f s to %g Hz", states.num_steps, dt, hz)
    return resample_states(states, hz), True


# ------------------------------------------------------------------------------------------ scenarios
@dataclass(frozen=True)
class RealScenario:
    """One real log prepared for rollouts.

    Attributes:
        dataset: dataset id (:data:`DATASETS`, else the log's source).
        seq_id: the log's id.
        states: every agent on the 10 Hz grid, the ego (:data:`EGO_ID`) first.
        map: the log's :class:`MotionMap`.
        start_step: first predicted step.
        resampled: the source was not 10 Hz.
    """

    dataset: str
    seq_id: str
    states: AgentStates
    map: MotionMap
    start_step: int = START_STEP
    resampled: bool = False

    @property
    def last_given(self) -> int:
        """The last history step (``start_step - 1``), the ``start_step`` of ``scenario.rollout_metrics``."""
        return self.start_step - 1

    def request(self) -> RolloutRequest:
        """Every agent free but the ego, which replays its log."""
        return RolloutRequest(states=self.states, start_step=self.start_step,
                              fixed_rows=np.array([self.states.index(EGO_ID)]), map=self.map)


def scenario_of_log(log: SceneLog, start_step: int = START_STEP, dataset: str | None = None) -> RealScenario:
    """The :class:`RealScenario` of ``log`` (module docstring).

    Raises:
        ValueError: the log has fewer than ``start_step + 2`` steps on the 10 Hz grid (nothing to predict).
    """
    states, resampled = on_step_grid(AgentStates.from_log(log))
    if states.num_steps < start_step + 2:
        raise ValueError(f"{log.seq_id}: {states.num_steps} steps at {STEP_HZ:g} Hz, need at least "
                         f"{start_step + 2} to predict from step {start_step}")
    return RealScenario(dataset=dataset or DATASETS.get(log.source, log.source), seq_id=log.seq_id, states=states,
                        map=motion_map_of(log), start_step=start_step, resampled=resampled)


def load_real_log(path: str | Path) -> SceneLog:
    """A real log by the source that recognises it (``simsplat_core.data.registry``: a Waymo Open Motion scenario
    TFRecord, an Argoverse 2 sensor log or motion-forecasting scenario, ...). A file no source recognises is read
    as a Waymo Open Motion scenario and a directory as an Argoverse 2 sensor log, so that their loaders name the
    damage.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        CorruptLogError: the loader's error, naming the file and the place in it.
    """
    from simsplat_core.data.registry import detect_source, load_log  # noqa: PLC0415  # loaders load on use

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist")
    return load_log(detect_source(path) or ("av2" if path.is_dir() else "waymo-scenario"), path)


# ------------------------------------------------------------------------------------------ scores
@dataclass(frozen=True)
class RolloutScore:
    """Scores of one rollout (or of the log itself) of one scenario.

    Attributes:
        dataset, seq_id, method: what was scored (``method`` :data:`LOG_METHOD` or a refinement mode).
        failures: scenario-level failures.
        agents: agents checked (all rows).
        collided / offroad: agents that collide with anyone / leave the road at some step.
        errors: ADE / FDE per agent (``None`` for the log row).
        progress: progress and stops (``None`` for the log row: the log's own are 1 and its stops).
        replayed: agents the predictor replayed, with the reason.
        predictor: the predictor's name (``""`` for the log row).
    """

    dataset: str
    seq_id: str
    method: str
    failures: ScenarioFailures
    agents: int
    collided: int
    offroad: int
    errors: DisplacementErrors | None
    progress: Progress
    replayed: dict[str, str]
    predictor: str = ""


def score_rollout(scenario: RealScenario, rollout: Rollout | None) -> RolloutScore:
    """Scores of ``rollout`` against the log, or of the log itself when ``rollout`` is ``None``; failures of both
    without a baseline (module docstring)."""
    log = scenario.states
    states = log if rollout is None else rollout.states
    # failures are checked on the steps the log observed, for the log and a rollout alike: a predictor fills
    # an agent's gaps, and a gap is often one object tracked under two ids that take turns (a cyclist and its
    # rider labelled a pedestrian), which would collide only in the filled-in rollout
    observed = replace(states, valid=states.valid & log.valid)
    failures = scenario_failures(observed, scenario.map.context)
    agents = score_agents(observed, scenario.map.context)
    # ADE and progress over the agents observed at the last history step (as Waymo motion scores them): an
    # agent that appears later is replayed by every predictor and would only dilute the means.
    seen = np.flatnonzero(log.valid[:, scenario.last_given])
    errors = None if rollout is None else displacement_errors(states.take(seen), log.take(seen),
                                                              scenario.last_given, HORIZONS_S)
    return RolloutScore(dataset=scenario.dataset, seq_id=scenario.seq_id,
                        method=LOG_METHOD if rollout is None else ROLLOUT_METHOD, failures=failures,
                        agents=agents.agents, collided=agents.collided, offroad=agents.offroad, errors=errors,
                        progress=progress_and_stops(states.take(seen), log.take(seen), scenario.last_given),
                        replayed={} if rollout is None else dict(rollout.replayed),
                        predictor="" if rollout is None else rollout.predictor)


def roll_out(scenario: RealScenario, predictor: MotionPredictor, stalls: list[Stall] | None = None) -> Rollout:
    """``predictor`` on ``scenario`` (the ego fixed); checks that the answer keeps the agents and steps. With
    ``stalls`` and a predictor that traces its limits (``traced_rollout``), the rollout's stalled agents
    (``eval.refinement.diagnosis``) are appended to it."""
    request = scenario.request()
    traced = getattr(predictor, "traced_rollout", None)
    if stalls is not None and traced is not None:
        rollout, trace = traced(request)
        seq_id, _, window = scenario.seq_id.rpartition("@")
        stalls += diagnose(scenario.states, rollout, trace, scenario.start_step, dataset=scenario.dataset,
                           seq_id=seq_id if window.isdigit() else scenario.seq_id,
                           window=int(window) if window.isdigit() else 0)
    else:
        rollout = predictor.rollout(request)
    got = rollout.states
    if got.object_ids != request.states.object_ids or got.num_steps != request.states.num_steps:
        raise ValueError(f"predictor {predictor.name!r} changed the agents or steps of {scenario.seq_id}")
    ego = request.states.index(EGO_ID)
    if not np.allclose(got.xy[ego], request.states.xy[ego]):
        raise ValueError(f"predictor {predictor.name!r} moved the fixed ego of {scenario.seq_id}")
    return rollout


# ------------------------------------------------------------------------------------------ rows
def _pooled(values: list[np.ndarray]) -> float | None:
    flat = np.concatenate(values) if values else np.zeros(0)
    flat = flat[np.isfinite(flat)]
    return float(flat.mean()) if flat.size else None


def _nan(value: float | None) -> float:
    return math.nan if value is None else float(value)


def row_of(scores: Sequence[RolloutScore]) -> dict[str, Any]:
    """One table row from the scores of one dataset, method and predictor over its scenarios (module docstring)."""
    if not scores:
        raise ValueError("a motion row needs at least one scenario")
    first = scores[0]
    row: dict[str, Any] = {"dataset": first.dataset, "method": first.method, "predictor": first.predictor,
                           "scenarios": len(scores), "refused": 0}
    row.update(rates([s.failures for s in scores]))
    row["progress"] = _nan(_pooled([s.progress.ratios for s in scores]))
    row["stopped_share"] = _nan(_pooled([s.progress.stopped.astype(np.float64) for s in scores]))
    for h in HORIZONS_S:
        col = [s.errors.ade[:, s.errors._column(h)] for s in scores if s.errors is not None]
        row[f"ade_{h:g}s"] = _pooled(col) if col else None
    agents = sum(s.agents for s in scores)
    row["agent_collision"] = sum(s.collided for s in scores) / agents if agents else math.nan
    row["agent_offroad"] = sum(s.offroad for s in scores) / agents if agents else math.nan
    return row


def per_type_errors(scores: Sequence[RolloutScore]) -> dict[str, dict[str, float | None]]:
    """``{agent type: {"ade_3s", "fde_3s", "ade_8s", "fde_8s", "agents"}}`` pooled over the scores' agents."""
    out: dict[str, dict[str, float | None]] = {}
    with_errors = [s.errors for s in scores if s.errors is not None]
    kinds = sorted({t for e in with_errors for t in e.types})
    for kind in kinds:
        entry: dict[str, float | None] = {"agents": float(sum(t == kind for e in with_errors for t in e.types))}
        for h in HORIZONS_S:
            for name, arr in (("ade", "ade"), ("fde", "fde")):
                vals = [getattr(e, arr)[np.array([t == kind for t in e.types]), e._column(h)] for e in with_errors]
                entry[f"{name}_{h:g}s"] = _pooled(vals)
        out[kind] = entry
    return out


@dataclass(frozen=True)
class RealEvaluation:
    """What :func:`real_rows` returns.

    Attributes:
        rows: table rows (``dataset``, ``method``, ``predictor``, ...), per dataset: the log row first, then each
            predictor's rollout (method :data:`ROLLOUT_METHOD`).
        per_type: ``{dataset: {predictor: per_type_errors}}`` (the side output).
        scores: every :class:`RolloutScore`.
        stalls: agents stopped in a rollout but moving in the log (``diagnose=True`` only).
    """

    rows: list[dict[str, Any]]
    per_type: dict[str, dict[str, dict[str, dict[str, float | None]]]]
    scores: list[RolloutScore]
    stalls: list[Stall] = field(default_factory=list)


def real_rows(scenarios: Sequence[RealScenario], predictors: Sequence[MotionPredictor],
              progress: Callable[[int, int, str], None] | None = None, *, diagnose: bool = False) -> RealEvaluation:
    """The log row and one row per predictor for each dataset of ``scenarios`` (module docstring); with
    ``diagnose``, the stalled agents of every traced rollout too.

    A predictor named :data:`LOG_METHOD` (``LogReplayPredictor``) adds no row: replaying the log is the log
    row (its ADE undefined).
    """
    scores: list[RolloutScore] = []
    stalls: list[Stall] | None = [] if diagnose else None
    rolled = [p for p in predictors if p.name != LOG_METHOD]  # the log replay's row is the log row
    total = len(scenarios) * len(rolled)
    done = 0
    for scenario in scenarios:
        scores.append(score_rollout(scenario, None))
        for predictor in rolled:
            scores.append(score_rollout(scenario, roll_out(scenario, predictor, stalls)))
            done += 1
            if progress is not None:
                progress(done, total, f"{scenario.seq_id} {predictor.name}")
    groups: dict[tuple[str, str, str], list[RolloutScore]] = {}
    for s in scores:
        groups.setdefault((s.dataset, s.method, s.predictor), []).append(s)
    rows = [row_of(g) for g in groups.values()]
    per_type: dict[str, dict[str, dict[str, dict[str, float | None]]]] = {}
    for (dataset, method, name), group in groups.items():
        if method != LOG_METHOD or any(s.errors is not None for s in group):
            per_type.setdefault(dataset, {})[name or method] = per_type_errors(group)
    return RealEvaluation(rows=rows, per_type=per_type, scores=scores, stalls=stalls or [])


def replayed_summary(scores: Sequence[RolloutScore]) -> Mapping[str, Any]:
    """Replayed agents per (dataset, predictor), for the run's manifest."""
    out: dict[str, Any] = {}
    for s in scores:
        if s.replayed:
            out.setdefault(f"{s.dataset}/{s.predictor or s.method}", {})[s.seq_id] = len(s.replayed)
    return out


__all__ = ["DATASETS", "HORIZONS_S", "LOG_METHOD", "ROLLOUT_METHOD", "START_STEP", "RealEvaluation", "RealScenario",
           "RolloutScore", "load_real_log", "on_step_grid", "per_type_errors", "real_rows",
           "resample_states", "roll_out", "replayed_summary", "row_of", "scenario_of_log", "score_rollout"]
