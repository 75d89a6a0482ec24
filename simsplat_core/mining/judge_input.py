"""A :class:`~simsplat_core.mining.vlm_protocol.JudgeRequest` from an executed edit, so the mining loop asks any
``VLMClient`` the same way.

    frames = render_frames(edited.graph, log, picked_frames)              # editing.renders
    pixels = visible_pixels_of([m for f in frames for m in f.node_id], edited.states, targets_of(edited))
    request = judge_request_from_edit(edited, [f.rgb[0] for f in frames], bev, visible_pixels=pixels)
    client.judge(request)

The request holds, from the :class:`~simsplat_core.editing.result.EditedScene`:

* the targets -- every agent a command inserted, changed or removed, per command (``command_targets``) -- with
  their edited trajectories (a removed one all NaN) and, where the log has them, their log trajectories
  (``before``);
* the surrounding agents: those that reacted (``refined``) and up to ``max_surrounding`` others that come within
  ``near_m`` of a target, nearest first (the ego included);
* the validation as text lines and as :class:`~simsplat_core.mining.vlm_protocol.ValidationFailure` values, and
  the executed program;
* given the log's ego poses and map (``labeller``), the targets' motion classes from the trajectory auto-labeller
  (``motion_labels``), so a judge checks a requested manoeuvre the way the editing benchmark does.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from simsplat_core.editing.commands import EditProgram
from simsplat_core.editing.result import EditedScene
from simsplat_core.language.motion_labels import label_trajectory
from simsplat_core.mining.vlm_protocol import AgentTrajectory, JudgeRequest, ValidationFailure
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import ValidationReport
from simsplat_core.scenario.trajectory import agent_kind, agent_trajectory

#: Surrounding agents come within this distance (m) of a target at a common step.
NEAR_M = 25.0
#: At most this many surrounding agents besides the reacting ones.
MAX_SURROUNDING = 8


def targets_of(edited: EditedScene) -> list[tuple[str, ...]]:
    """Per command, the object ids it inserted, changed or removed (in that order, without repeats)."""
    return [tuple(dict.fromkeys((*o.new_object_ids, *o.changed_object_ids))) for o in edited.outcomes]


def trajectory_of(states: AgentStates, object_id: str, is_target: bool) -> AgentTrajectory:
    """The row of ``object_id`` as an :class:`AgentTrajectory` (NaN where it is not valid)."""
    r = states.index(object_id)
    valid = states.valid[r]
    xy = np.where(valid[:, None], states.xy[r], np.nan)  # [T, 2]
    heading = np.where(valid, states.heading[r], np.nan)  # [T]
    return AgentTrajectory(object_id, states.categories[r], states.sources[r], xy, is_target, heading)


def _absent(states: AgentStates, before: AgentStates, object_id: str) -> AgentTrajectory:
    """A removed agent: all NaN over ``states``' steps, its log category."""
    category = before.categories[before.index(object_id)] if object_id in before.object_ids else "other"
    return AgentTrajectory(object_id, category, "edited", np.full((states.num_steps, 2), np.nan), True)


def _surrounding(states: AgentStates, targets: Sequence[str], near_m: float, most: int) -> list[str]:
    """Reacting agents, then up to ``most`` others within ``near_m`` of a present target, nearest first."""
    present = [states.index(o) for o in targets if o in states.object_ids]
    others = [r for r in range(states.num_agents) if states.object_ids[r] not in targets]
    refined = [states.object_ids[r] for r in others if states.sources[r] == "refined"]
    if not present:
        return refined
    xy = np.where(states.valid[..., None], states.xy, np.nan)  # [A, T, 2]
    gaps = np.linalg.norm(xy[others][:, None] - xy[present][None], axis=-1)  # [O, P, T]
    closest = np.where(np.isfinite(gaps), gaps, np.inf).reshape(len(others), -1).min(axis=1, initial=np.inf)  # [O]
    near = [(float(d), states.object_ids[r]) for r, d in zip(others, closest) if d <= near_m]
    extra = [o for _, o in sorted(near) if o not in refined][:most]
    return refined + extra


def validation_failures(report: ValidationReport) -> list[ValidationFailure]:
    """The report's failures as values, one per failed check of each agent."""
    out = []
    for a in report.agents:
        lines = iter(a.failures(report.frame_idx))
        if a.collision:
            out.append(ValidationFailure(a.object_id, "collision", a.collision_step, a.collision_with, next(lines)))
        if a.offroad:
            out.append(ValidationFailure(a.object_id, "offroad", a.offroad_step, None, next(lines)))
        if a.kinematic:
            out.append(ValidationFailure(a.object_id, "kinematic", a.kinematic_step, None, next(lines)))
    return out


def validation_lines(report: ValidationReport) -> tuple[str, ...]:
    """The failures as text, or one line saying every check passed."""
    failures = report.failures()
    if failures:
        return tuple(failures)
    return (f"{len(report.agents)} agent(s) checked: no collision, no off-road, kinematics within bounds",)


def visible_pixels_of(node_id_maps: Iterable[np.ndarray], states: AgentStates, object_ids: Iterable[str]
                      ) -> dict[str, int]:
    """Pixels each of ``object_ids`` covers in ``node_id_maps`` (any number of ``[H, W]`` int node-id renders,
    ``-1`` background; ``editing.renders.FrameRender.node_id``); agents without a node (or absent) get 0."""
    ids = [o for o in dict.fromkeys(object_ids)]
    maps = [np.asarray(m).ravel() for m in node_id_maps]
    values, counts = np.unique(np.concatenate(maps), return_counts=True) if maps else (np.zeros(0), np.zeros(0))
    by_node = {int(v): int(c) for v, c in zip(values, counts)}
    out = {}
    for oid in ids:
        node = int(states.node_ids[states.index(oid)]) if oid in states.object_ids else -1
        out[oid] = by_node.get(node, 0) if node >= 0 else 0
    return out


def motion_labels_of(states: AgentStates, object_ids: Iterable[str], ego_poses: np.ndarray,
                     map_ctx: MapContext) -> dict[str, str]:
    """Object id -> the trajectory auto-labeller's motion class (``language.motion_labels.label_trajectory`` of
    ``scenario.trajectory.agent_trajectory``: what the editing benchmark checks) for those of ``object_ids``
    present in ``states`` with a motion vocabulary and two valid steps; ``ego_poses`` is the log's ``[F, 4, 4]``."""
    out = {}
    for oid in object_ids:
        if oid not in states.object_ids:
            continue
        row = states.index(oid)
        if agent_kind(states.categories[row]) is None or states.valid[row].sum() < 2:
            continue
        out[oid] = label_trajectory(agent_trajectory(states, row, map_ctx), ego_poses, map_ctx).motion
    return out


def judge_request_from_edit(edited: EditedScene, renders: Sequence[np.ndarray], bev: np.ndarray, *,
                            visible_pixels: Mapping[str, int] | None = None, prompt: str | None = None,
                            near_m: float = NEAR_M, max_surrounding: int = MAX_SURROUNDING,
                            labeller: tuple[np.ndarray, MapContext] | None = None) -> JudgeRequest:
    """The :class:`JudgeRequest` of ``edited`` (module docstring) with its ``renders`` (``[H, W, 3]`` each) and
    ``bev``; ``prompt`` defaults to the edit's (or, for a command-only edit, its outcomes' summaries). Given
    ``labeller`` (the log's ``[F, 4, 4]`` ego poses and its map), the targets' ``motion_labels``
    (:func:`motion_labels_of`)."""
    states, before = edited.states, edited.original_states
    per_command = targets_of(edited)
    targets = list(dict.fromkeys(o for ids in per_command for o in ids))
    trajectories = [trajectory_of(states, o, True) if o in states.object_ids else _absent(states, before, o)
                    for o in targets]
    context = _surrounding(states, targets, near_m, max_surrounding)
    trajectories += [trajectory_of(states, o, False) for o in context]
    logged = [trajectory_of(before, o, o in targets) for o in (*targets, *context) if o in before.object_ids]
    dt = float(np.median(np.diff(states.times))) if states.num_steps > 1 else 0.1
    words = prompt or edited.prompt or "; ".join(edited.summary_lines()) or "an edit"
    program = EditProgram(prompt=words, commands=list(edited.commands))
    return JudgeRequest(prompt=words, renders=renders, bev=bev, trajectories=trajectories,
                        validation=validation_lines(edited.validation), dt_s=dt, before=logged,
                        failures=validation_failures(edited.validation), program=program,
                        command_targets=per_command, visible_pixels=visible_pixels,
                        motion_labels=None if labeller is None else motion_labels_of(states, targets, *labeller))


__all__ = ["MAX_SURROUNDING", "NEAR_M", "judge_request_from_edit", "motion_labels_of", "targets_of", "trajectory_of",
           "validation_failures", "validation_lines", "visible_pixels_of"]
