"""What the mining loop tells a VLM: the system prompts, the tool names and the text of each request.

Pure text builders (no HTTP, no images): ``mining.openai_vlm`` puts them into chat messages with the images
inline. Trajectories are summarised as text -- a few sampled positions per agent, the distance travelled
and the mean speed -- since a VLM reads numbers better than it reads them off a plot.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from simsplat_core.mining.vlm_protocol import AgentTrajectory, JudgeRequest, ProposalRequest, SceneSummary

PROPOSE_TOOL = "propose_edits"
COMMAND_TOOL = "emit_edit_program"
JUDGE_TOOL = "judge_edit"

PROPOSE_SYSTEM = f"""\
You design test scenarios for autonomous-driving software. A real driving log has been reconstructed as an \
editable 3D scene: the simulator can insert, remove or replace objects and change how vehicles and pedestrians \
move, and the traffic around an edit reacts to it. From the camera views and the scene facts, propose edit \
prompts that make the scene safety-critical for the ego vehicle (the car carrying the cameras) while staying \
feasible in this very scene.
Rules:
- One sentence per prompt, in plain English, describing one edit or a few coordinated ones.
- Make the prompts diverse: cover insert, remove, replace and modify (speed, stopping, start time, lane change, \
turn, reversing, crossing the street) for vehicles, pedestrians and static objects (cones, barriers, signs).
- Refer to existing objects by what the views or the facts show (colour, type, where they are relative to the ego).
- Never edit the ego vehicle. Keep speeds, distances and places feasible: vehicles on the road, pedestrians on \
sidewalks or crossing it, nothing inside buildings or other objects.
- No two prompts may ask for the same edit.
Answer only by calling the function {PROPOSE_TOOL}."""

COMMAND_SYSTEM = f"""\
You translate one scenario-edit prompt into an edit program for a driving simulator. Call the function \
{COMMAND_TOOL} with the commands that do what the prompt says, applied in order.
- op: insert (needs asset, placed with placement), remove (needs target), replace (target and asset: the target \
keeps its path), modify (target and behaviour and/or placement).
- Targets and anchors: a short description of the object as the scene facts or the prompt give it ("the white \
van ahead"); object_id only when the facts give one. The description "ego" names the ego vehicle, which may be \
an anchor but is never a target.
- Positions are in the ego frame (x forward, y left, metres), headings in degrees counter-clockwise from the \
ego's x axis, times in seconds from the start of the log.
- Use only the fields of the schema and leave out what the prompt does not say."""

JUDGE_SYSTEM = f"""\
You review an edited driving scenario produced by a simulator. You see camera renders of the edited scene and a \
bird's-eye view (BEV, the last image), and read the trajectories of the edited agents and of the agents around \
them, and the automatic validation results. Decide:
- follows_prompt: does the scenario do what the prompt asks?
- plausibility: 1 = implausible (collisions nobody reacts to, objects off the road or floating, impossible \
motion), 2 = doubtful, 3 = plausible with minor flaws, 4 = fully plausible as a real driving scene.
- reasons: short reasons for both answers.
- suggestions: parameter changes for the next attempt that would fix what is wrong -- the inserted asset, the \
speed, the start time, the placement offset, the placement anchor, or other -- and none when nothing is wrong.
Answer only by calling the function {JUDGE_TOOL}."""

#: Positions quoted per agent and agents listed in a judge request.
TRAJECTORY_SAMPLES = 5
MAX_AGENTS = 12


def propose_text(request: ProposalRequest) -> str:
    """The user turn of a proposal (the views follow it as images)."""
    n = len(request.views)
    return (f"Scene {request.summary.seq_id}: {n} camera view{'s' if n != 1 else ''} of one moment follow.\n"
            f"Scene facts:\n{request.summary.text()}\n\n"
            f"Propose up to {request.count} distinct edit prompts.")


def command_text(prompt: str, summary: SceneSummary) -> str:
    """The user turn of a prompt-to-command translation."""
    return f"Scene {summary.seq_id} facts:\n{summary.text()}\n\nEdit prompt: {prompt.strip()}"


def trajectory_line(trajectory: AgentTrajectory, dt_s: float, samples: int = TRAJECTORY_SAMPLES) -> str:
    """``"- id [target] category, source: t=0.0s (x, y); ...; travelled D m, mean speed V m/s"``.

    ``samples`` positions are spread evenly over the agent's present (finite) steps.
    """
    role = " [target]" if trajectory.is_target else ""
    head = f"- {trajectory.object_id}{role} {trajectory.category}, {trajectory.source}"
    present = np.flatnonzero(np.isfinite(trajectory.xy).all(axis=1))  # [P] steps where the agent exists
    if present.size == 0:
        return f"{head}: absent"
    picks = np.unique(np.linspace(0, present.size - 1, max(1, samples)).round().astype(int))
    points = "; ".join(f"t={present[i] * dt_s:.1f}s ({trajectory.xy[present[i], 0]:.1f}, "
                       f"{trajectory.xy[present[i], 1]:.1f})" for i in picks)
    xy = trajectory.xy[present]  # [P, 2]
    travelled = float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum())
    duration = float(present[-1] - present[0]) * dt_s
    speed = f", mean speed {travelled / duration:.1f} m/s" if duration > 0 else ""
    return f"{head}: {points}; travelled {travelled:.1f} m{speed}"


def trajectory_lines(trajectories: Sequence[AgentTrajectory], dt_s: float, max_agents: int = MAX_AGENTS) -> list[str]:
    """One :func:`trajectory_line` per agent, targets first, at most ``max_agents`` (the rest counted)."""
    ordered = sorted(trajectories, key=lambda t: not t.is_target)  # stable: keeps the caller's order otherwise
    lines = [trajectory_line(t, dt_s) for t in ordered[:max_agents]]
    if len(ordered) > max_agents:
        lines.append(f"- ... and {len(ordered) - max_agents} more agent(s) not listed")
    return lines


def judge_text(request: JudgeRequest) -> str:
    """The user turn of a judgement (the renders and then the BEV follow it as images)."""
    n = len(request.renders)
    parts = [f"Edit prompt: {request.prompt.strip()}"]
    if request.command_json.strip():
        parts.append(f"Executed edit program (JSON):\n{request.command_json.strip()}")
    parts.append(f"Images: {n} camera render{'s' if n != 1 else ''} of the edited scene, then the bird's-eye view "
                 f"(the last image).")
    traj = trajectory_lines(request.trajectories, request.dt_s) or ["(none given)"]
    parts.append("Trajectories (world x, y in metres):\n" + "\n".join(traj))
    checks = [f"- {line}" for line in request.validation] or ["(none given)"]
    parts.append("Validation:\n" + "\n".join(checks))
    return "\n\n".join(parts)


__all__ = [
    "COMMAND_SYSTEM",
    "COMMAND_TOOL",
    "JUDGE_SYSTEM",
    "JUDGE_TOOL",
    "PROPOSE_SYSTEM",
    "PROPOSE_TOOL",
    "command_text",
    "judge_text",
    "propose_text",
    "trajectory_line",
    "trajectory_lines",
]
