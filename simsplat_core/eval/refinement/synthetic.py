"""The motion benchmark on the synthetic scenes (the paper's Table 4 analogue): failures after an edit, per
refinement mode.

    cases = motion_cases(truths, editing_prompts)                  # modify / insert prompts + interactions
    outcomes = evaluate_motion(contexts, cases)                    # one per (case, mode); ctx's predictor
    rows = synthetic_rows(outcomes, log_outcomes(contexts))        # the log row, then one per mode

Each case is applied by the editor itself (parse, ground, place, plan; no rendering) in each of :data:`BENCH_MODES`:
refinement ``"none"`` (others replay the log), ``"single-agent"`` (only the edited agents avoid conflicts),
``"full"`` (every other agent reacts, the ego too: the editor's default) and ``"full-ego-log"`` (every other agent
reacts but the ego replays its log: ``simsplat edit --ego-replays``). Failures are measured on every agent of the
edited scenario (a scenario fails when any agent fails, not only the edited one), with the Waymax definitions of
``scenario.rollout_metrics.scenario_failures``; pairs that already overlapped in the log at that step are the log's,
not the edit's. Progress and the share of agents stopped for good are measured against the log, over the agents the
edit did not change, so that "everyone stands still" cannot pass as safe. A case the editor refuses has no scenario
and is counted apart (``refused``) in every mode. Each outcome also names every failing agent and what happened to
it (``scoring.score_agents``), for the outcomes table.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.apply import Editor
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.options import DEFAULT_OPTIONS
from simsplat_core.editing.result import EditRefused
from simsplat_core.eval.editing.prompts import EditPrompt
from simsplat_core.eval.refinement.interactions import InteractionPrompt
from simsplat_core.eval.refinement.scoring import score_agents
from simsplat_core.motion.refine import EDIT_SOURCES, Refinement
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.rollout_metrics import ScenarioFailures, progress_and_stops, rates, scenario_failures

logger = logging.getLogger(__name__)

#: Categories of the editing benchmark whose prompts the motion benchmark applies.
EDITING_CATEGORIES: tuple[str, ...] = ("add_vehicle", "add_static", "add_pedestrian", "modify_vehicle",
                                       "modify_pedestrian")
#: ``progress(done, total, label)`` after each (case, mode).
Progress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class MotionCase:
    """One edit of the benchmark: ``source`` ``"editing"`` (an editing-benchmark prompt, ``kind`` its category)
    or ``"interaction"`` (``kind`` one of ``interactions.INTERACTION_KINDS``)."""

    case_id: str
    seq_id: str
    source: str
    kind: str
    text: str


@dataclass(frozen=True)
class MotionOutcome:
    """One case under one refinement mode.

    Attributes:
        refused: the editor's refusal message (``""`` when carried out; then the other fields are set).
        failures: failures of every agent of the edited scenario.
        progress: mean progress along the log's routes of the agents that move in the log.
        stopped_share: share of those agents stopped for good.
        refined: ids of agents that reacted; replayed: agents the predictor left to their log, with reasons.
        seconds: time of the edit (refinement included).
        agents / collided / offroad_agents: agents checked, that collide, that leave the road.
        details: one line per failing agent (``scoring.AgentScores.details``).
        predictor: the predictor that refined (``""`` for mode ``"none"`` and the log).
    """

    case: MotionCase
    mode: str
    refused: str = ""
    failures: ScenarioFailures | None = None
    progress: float = float("nan")
    stopped_share: float = float("nan")
    refined: tuple[str, ...] = ()
    replayed: tuple[str, ...] = ()
    seconds: float = 0.0
    agents: int = 0
    collided: int = 0
    offroad_agents: int = 0
    details: tuple[str, ...] = ()
    predictor: str = ""


def motion_cases(editing_prompts: Sequence[EditPrompt], interactions: Sequence[InteractionPrompt]
                 ) -> list[MotionCase]:
    """The modify / insert prompts of the editing benchmark (:data:`EDITING_CATEGORIES`) and the interaction
    prompts, as cases."""
    out = [MotionCase(p.prompt_id, p.seq_id, "editing", p.category, p.text) for p in editing_prompts
           if p.category in EDITING_CATEGORIES]
    out += [MotionCase(p.prompt_id, p.seq_id, "interaction", p.kind, p.text) for p in interactions]
    return out


#: Modes of the benchmark: ``mode -> (refinement, ego_reacts)`` (module docstring).
BENCH_MODES: dict[str, tuple[str, bool]] = {
    "none": ("none", False), "single-agent": ("single-agent", False), "full": ("full", True),
    "full-ego-log": ("full", False)}


def evaluate_case(ctx: EditContext, case: MotionCase, mode: str) -> MotionOutcome:
    """Apply ``case`` in ``ctx`` in benchmark ``mode`` (:data:`BENCH_MODES`) and measure the edited scenario."""
    refinement, ego_reacts = BENCH_MODES[mode]
    options = dataclasses.replace(DEFAULT_OPTIONS, refinement=refinement, ego_reacts=ego_reacts, check_looks=False)
    t = time.perf_counter()
    try:
        edited = Editor(ctx, options).edit(case.text)
    except EditRefused as exc:
        return MotionOutcome(case, mode, refused=f"{exc.reason}: {exc}", seconds=time.perf_counter() - t)
    return measure(case, mode, edited.states, edited.original_states, ctx.map_ctx, edited.refinement,
                   time.perf_counter() - t)


def measure(case: MotionCase, mode: str, states: AgentStates, log: AgentStates, context: MapContext,
            reaction: Refinement | None, seconds: float) -> MotionOutcome:
    """The outcome of ``case`` in ``mode``: the edited (and refined) ``states`` against the unedited ``log`` on the
    same steps (module docstring)."""
    failures = scenario_failures(states, context, baseline=log)
    agents = score_agents(states, context, baseline=log)
    start = reaction.start_step if reaction is not None else 1
    # the traffic's progress: agents the edit changed do what they were told (a stop edit stops for good)
    kept = [r for r, (o, s) in enumerate(zip(states.object_ids, states.sources))
            if o in log.object_ids and s not in EDIT_SOURCES]
    progress = progress_and_stops(states.take(kept), log, start)
    return MotionOutcome(case, mode, failures=failures, progress=progress.progress,
                         stopped_share=progress.stopped_share,
                         refined=reaction.refined_ids if reaction is not None else (),
                         replayed=tuple(sorted(reaction.replayed)) if reaction is not None else (), seconds=seconds,
                         agents=agents.agents, collided=agents.collided, offroad_agents=agents.offroad,
                         details=agents.details, predictor=reaction.predictor if reaction is not None else "")


def evaluate_motion(contexts: Mapping[str, EditContext], cases: Sequence[MotionCase],
                    modes: Sequence[str] = tuple(BENCH_MODES), progress: Progress | None = None
                    ) -> list[MotionOutcome]:
    """Every case in every mode (``contexts`` by sequence id)."""
    unknown = sorted(set(modes) - set(BENCH_MODES))
    if unknown:
        raise ValueError(f"unknown refinement modes {unknown}; known: {list(BENCH_MODES)}")
    out = []
    total = len(cases) * len(modes)
    for case in cases:
        if case.seq_id not in contexts:
            raise KeyError(f"case {case.case_id}: no scene {case.seq_id!r} (scenes: {sorted(contexts)})")
        for mode in modes:
            out.append(evaluate_case(contexts[case.seq_id], case, mode))
            if progress is not None:
                progress(len(out), total, case.case_id)
    return out


def log_outcome(seq_id: str, states: AgentStates, context: MapContext) -> MotionOutcome:
    """The unedited log's own failures (every overlap counted), progress 1 and its own stopped share."""
    agents = score_agents(states, context)
    stops = progress_and_stops(states, states, 1)
    return MotionOutcome(MotionCase(f"{seq_id}:log", seq_id, "log", "log", ""), "log",
                         failures=scenario_failures(states, context), progress=stops.progress,
                         stopped_share=stops.stopped_share, agents=agents.agents, collided=agents.collided,
                         offroad_agents=agents.offroad, details=agents.details)


def log_outcomes(contexts: Mapping[str, EditContext]) -> list[MotionOutcome]:
    """The unedited logs' outcomes (the ``log`` row), one per scene (:func:`log_outcome`)."""
    return [log_outcome(seq_id, ctx.states, ctx.map_ctx) for seq_id, ctx in contexts.items()]


def _mean(values: list[float]) -> float | None:
    finite = [v for v in values if np.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def _agent_share(outcomes: Sequence[MotionOutcome], field: str) -> float:
    agents = sum(o.agents for o in outcomes)
    return sum(getattr(o, field) for o in outcomes) / agents if agents else float("nan")


def _row(dataset: str, method: str, predictor: str, kept: Sequence[MotionOutcome], refused: int) -> dict[str, object]:
    failures = [o.failures for o in kept if o.failures is not None]
    return {"dataset": dataset, "method": method, "predictor": predictor, "scenarios": len(kept), "refused": refused,
            **rates(failures), "progress": _mean([o.progress for o in kept]),
            "stopped_share": _mean([o.stopped_share for o in kept]), "ade_3s": None, "ade_8s": None,
            "agent_collision": _agent_share(kept, "collided"), "agent_offroad": _agent_share(kept, "offroad_agents")}


def synthetic_rows(outcomes: Sequence[MotionOutcome], logs: Sequence[MotionOutcome] = (),
                   dataset: str = "synthetic", predictor: str = "") -> list[dict[str, object]]:
    """Table rows (``motion.parquet`` columns): ``log`` (from ``logs``, :func:`log_outcomes`) then one per mode,
    over the cases every mode carried out (a case refused in some mode is left out of all, so the modes are
    compared on the same scenarios; ``refused`` counts them). ``predictor`` names the refining predictor (default:
    the outcomes' own); the ``none`` row has none."""
    rows: list[dict[str, object]] = []
    if logs:
        rows.append(_row(dataset, "log", "", logs, 0))
    modes = list(dict.fromkeys(o.mode for o in outcomes))
    by_case: dict[str, dict[str, MotionOutcome]] = {}
    for o in outcomes:
        by_case.setdefault(o.case.case_id, {})[o.mode] = o
    done = [c for c, per in by_case.items() if all(not per[m].refused for m in modes if m in per)]
    refused = len(by_case) - len(done)
    for mode in modes:
        kept = [by_case[c][mode] for c in done if mode in by_case[c]]
        if not kept:
            continue
        name = "" if mode == "none" else predictor or next((o.predictor for o in kept if o.predictor), "")
        rows.append(_row(dataset, mode, name, kept, refused))
    return rows


def outcome_row(outcome: MotionOutcome, dataset: str = "synthetic") -> dict[str, object]:
    """One row of the outcomes table (``table.OUTCOME_COLUMNS``)."""
    f = outcome.failures or ScenarioFailures()
    c = outcome.case
    return {"case_id": c.case_id, "dataset": dataset, "seq_id": c.seq_id, "source": c.source, "kind": c.kind,
            "text": c.text, "mode": outcome.mode, "predictor": outcome.predictor, "refused": outcome.refused,
            "collision_vehicle": f.collision_vehicle, "collision_pedestrian": f.collision_pedestrian,
            "collision_static": f.collision_static, "offroad": f.offroad, "kinematic": f.kinematic,
            "failure": outcome.failures is not None and f.failure, "failed_agents": ",".join(f.failed_agents),
            "failure_details": " | ".join(outcome.details), "refined": len(outcome.refined),
            "progress": float(outcome.progress), "stopped_share": float(outcome.stopped_share),
            "seconds": float(outcome.seconds)}


__all__ = ["EDITING_CATEGORIES", "MotionCase", "MotionOutcome", "evaluate_case", "evaluate_motion", "log_outcome",
           "log_outcomes", "measure", "motion_cases", "outcome_row", "synthetic_rows"]
