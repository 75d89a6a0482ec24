"""The ``VLMClient`` protocol of the mining loop: propose edit prompts, turn one into commands, judge the result.

The loop asks a client three things:

1. :meth:`VLMClient.propose` -- from multi-view renders of a scene and a :class:`SceneSummary` (grounded facts
   as text), up to ``count`` candidate edit prompts ("a pedestrian jaywalks in front of the ego");
2. :meth:`VLMClient.to_command` -- one prompt as a validated :class:`~simsplat_core.editing.commands.EditProgram`;
3. :meth:`VLMClient.judge` -- from the edited renders, the bird's-eye view, the target's and surrounding
   agents' trajectories and the validation facts: does it follow the prompt, how plausible is it (1..4),
   why, and which parameters to change for the next attempt (:class:`Judgement`).

Implementations: the OpenAI-compatible HTTP client (``mining.openai_vlm``) and the rule-based offline client
(``mining.rule_client``). Besides what a VLM reads (images and text), the requests carry optional structured
facts -- :attr:`SceneSummary.facts`, :attr:`JudgeRequest.before` / ``failures`` / ``program`` /
``command_targets`` / ``visible_pixels`` -- that the rule-based client checks and an HTTP client may ignore.
Everything here is a frozen value: images are ``[H, W, 3]`` RGB arrays (uint8, or float in ``[0, 1]``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol, get_args, runtime_checkable

import numpy as np

from simsplat_core.editing.commands import EditProgram, program_to_json

if TYPE_CHECKING:
    from simsplat_core.mining.scene_fact_records import SceneFacts

#: What a suggested change is about (the knobs the loop can turn between attempts).
Parameter = Literal["asset", "speed", "start_time", "offset", "anchor", "other"]
PARAMETERS: tuple[str, ...] = get_args(Parameter)
#: Plausibility scale of :class:`Judgement`: 1 implausible .. 4 fully plausible.
PLAUSIBILITY_MIN, PLAUSIBILITY_MAX = 1, 4
#: What a validation failure is about (``scenario.metrics.AgentValidation``'s three checks).
FailureKind = Literal["collision", "offroad", "kinematic"]
FAILURE_KINDS: tuple[str, ...] = get_args(FailureKind)


def _rgb(image: np.ndarray, what: str) -> np.ndarray:
    """``image`` as an array after checking it is ``[H, W, 3]`` with ``H, W > 0``."""
    array = np.asarray(image)
    if array.ndim != 3 or array.shape[2] != 3 or array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(f"{what} must be an [H, W, 3] RGB image, got shape {array.shape}")
    return array


@dataclass(frozen=True)
class SceneSummary:
    """Grounded facts about one sequence, as text lines the VLM reads.

    Attributes:
        seq_id: the sequence.
        lines: one fact per line, e.g. ``"car-3: a white van, 12 m ahead in the ego lane, stopped"``,
            ``"map: 4-way intersection 30 m ahead, crosswalk on the right"``.
        facts: the same facts as values (``mining.scene_facts.summary`` fills both), for clients that reason on
            them rather than on text; not part of :meth:`text`, equality or the repr.
    """

    seq_id: str
    lines: tuple[str, ...] = ()
    facts: SceneFacts | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "lines", tuple(str(line) for line in self.lines))

    def text(self) -> str:
        """The facts as a bulleted block (``"(no facts)"`` when there are none)."""
        return "\n".join(f"- {line}" for line in self.lines) if self.lines else "(no facts)"


@dataclass(frozen=True, eq=False)
class ProposalRequest:
    """What :meth:`VLMClient.propose` looks at.

    Attributes:
        views: ``V >= 1`` images ``[H, W, 3]`` (uint8 or float in ``[0, 1]``): the scene's cameras at one frame
            (any sequence; stored as a tuple).
        summary: the scene's grounded facts.
        count: most prompts wanted (``>= 1``).
    """

    views: Sequence[np.ndarray]
    summary: SceneSummary
    count: int = 5

    def __post_init__(self) -> None:
        views = tuple(_rgb(v, f"ProposalRequest.views[{i}]") for i, v in enumerate(self.views))
        if not views:
            raise ValueError("ProposalRequest.views must hold at least one image")
        object.__setattr__(self, "views", views)
        if self.count < 1:
            raise ValueError(f"ProposalRequest.count must be >= 1, got {self.count}")


@dataclass(frozen=True, eq=False)
class AgentTrajectory:
    """One agent's path in a judged scenario.

    Attributes:
        object_id: the log's (or the insertion's) object id.
        category: ``"vehicle"``, ``"pedestrian"``, ``"cyclist"``, ``"static"`` ...
        source: ``"log"``, ``"edited"``, ``"inserted"`` or ``"refined"`` (the ``trajectories`` table's column).
        xy: ``[T, 2]`` world positions in metres, one row per step (NaN rows: the agent is absent then).
        is_target: the edit acted on this agent (else it is a surrounding agent).
        heading: optional ``[T]`` yaw in radians (NaN where absent); without it, directions come from ``xy``.
    """

    object_id: str
    category: str
    source: str
    xy: np.ndarray
    is_target: bool = False
    heading: np.ndarray | None = None

    def __post_init__(self) -> None:
        xy = np.asarray(self.xy, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"AgentTrajectory.xy of {self.object_id} must be [T, 2], got shape {xy.shape}")
        object.__setattr__(self, "xy", xy)
        if self.heading is not None:
            heading = np.asarray(self.heading, dtype=np.float64)
            if heading.shape != (len(xy),):
                raise ValueError(f"AgentTrajectory.heading of {self.object_id} must be [{len(xy)}], "
                                 f"got shape {heading.shape}")
            object.__setattr__(self, "heading", heading)

    @property
    def present(self) -> np.ndarray:
        """``[T]`` bool: steps where the agent exists (finite ``xy``)."""
        return np.isfinite(self.xy).all(axis=1)


@dataclass(frozen=True)
class ValidationFailure:
    """One failed validation check of an agent in the judged scenario (``scenario.metrics.AgentValidation``).

    Attributes:
        object_id: the failing agent.
        kind: :data:`FailureKind`.
        step: first failing step (``None``: not known).
        other_id: for a collision, the agent it first collides with.
        text: the validation's line for people.
    """

    object_id: str
    kind: FailureKind
    step: int | None = None
    other_id: str | None = None
    text: str = ""

    def __post_init__(self) -> None:
        if self.kind not in FAILURE_KINDS:
            raise ValueError(f"ValidationFailure.kind must be one of {FAILURE_KINDS}, got {self.kind!r}")


@dataclass(frozen=True, eq=False)
class JudgeRequest:
    """What :meth:`VLMClient.judge` looks at.

    Attributes:
        prompt: the edit prompt that was executed.
        renders: ``R >= 1`` images ``[H, W, 3]`` of the edited scene (cameras at telling frames; any sequence,
            stored as a tuple, like ``trajectories``).
        bev: ``[H, W, 3]`` bird's-eye view of the edited scenario (map, boxes, paths).
        trajectories: the target(s) and the surrounding agents (``is_target`` tells which).
        validation: facts from the validation metrics, one per line (``"no collision"``, ``"off-road: none"``).
        dt_s: seconds between trajectory steps.
        command_json: the executed :class:`EditProgram` as JSON ("" when not shown), so suggestions can refer
            to its parameters; filled from ``program`` when that is given and this is empty.
        before: the log trajectories of the same agents (those the log has), on the same steps. This field and
            the next four are structured facts for clients that check rather than look (optional;
            ``mining.judge_input.judge_request_from_edit`` fills them from an edit).
        failures: the validation's failures as values (``validation`` holds them as text).
        program: the executed :class:`EditProgram`.
        command_targets: per command of ``program``, the object ids it acted on (inserted, changed or removed).
        visible_pixels: object id -> pixels it covers in ``renders`` (``None``: not measured).
        motion_labels: object id -> the motion class the trajectory auto-labeller (``language.motion_labels``, the
            one the editing benchmark checks edits with) gives the agent's judged trajectory, for the targets it can
            label (``None``: not labelled).
    """

    prompt: str
    renders: Sequence[np.ndarray]
    bev: np.ndarray
    trajectories: Sequence[AgentTrajectory] = ()
    validation: tuple[str, ...] = ()
    dt_s: float = 0.1
    command_json: str = ""
    before: Sequence[AgentTrajectory] = ()
    failures: Sequence[ValidationFailure] = ()
    program: EditProgram | None = None
    command_targets: Sequence[tuple[str, ...]] = ()
    visible_pixels: Mapping[str, int] | None = None
    motion_labels: Mapping[str, str] | None = None

    def __post_init__(self) -> None:
        if not self.prompt.strip():
            raise ValueError("JudgeRequest.prompt is empty")
        renders = tuple(_rgb(r, f"JudgeRequest.renders[{i}]") for i, r in enumerate(self.renders))
        if not renders:
            raise ValueError("JudgeRequest.renders must hold at least one image")
        object.__setattr__(self, "renders", renders)
        object.__setattr__(self, "bev", _rgb(self.bev, "JudgeRequest.bev"))
        object.__setattr__(self, "trajectories", tuple(self.trajectories))
        object.__setattr__(self, "validation", tuple(str(v) for v in self.validation))
        if self.dt_s <= 0:
            raise ValueError(f"JudgeRequest.dt_s must be > 0, got {self.dt_s}")
        object.__setattr__(self, "before", tuple(self.before))
        object.__setattr__(self, "failures", tuple(self.failures))
        targets = tuple(tuple(str(o) for o in ids) for ids in self.command_targets)
        if targets and (self.program is None or len(targets) != len(self.program.commands)):
            raise ValueError(f"JudgeRequest.command_targets needs one entry per command of program, got "
                             f"{len(targets)} for {0 if self.program is None else len(self.program.commands)}")
        object.__setattr__(self, "command_targets", targets)
        if self.visible_pixels is not None:
            object.__setattr__(self, "visible_pixels", {str(k): int(v) for k, v in self.visible_pixels.items()})
        if self.motion_labels is not None:
            object.__setattr__(self, "motion_labels", {str(k): str(v) for k, v in self.motion_labels.items()})
        if self.program is not None and not self.command_json.strip():
            object.__setattr__(self, "command_json", program_to_json(self.program))

    def trajectory(self, object_id: str) -> AgentTrajectory | None:
        """The judged trajectory of ``object_id`` (``None``: not given)."""
        return next((t for t in self.trajectories if t.object_id == object_id), None)

    def log_trajectory(self, object_id: str) -> AgentTrajectory | None:
        """The log trajectory of ``object_id`` in ``before`` (``None``: not given, e.g. an inserted agent)."""
        return next((t for t in self.before if t.object_id == object_id), None)


@dataclass(frozen=True)
class ParameterChange:
    """A change the judge suggests for the next attempt.

    Attributes:
        parameter: which knob (:data:`Parameter`): the inserted ``asset``, the ``speed``, the ``start_time``,
            the placement ``offset``, the placement ``anchor``, or ``other``.
        value: the suggested value in words or numbers (``"8 m/s"``, ``"2 s later"``, ``"a smaller car"``).
        reason: why.
    """

    parameter: Parameter
    value: str
    reason: str = ""

    def __post_init__(self) -> None:
        if self.parameter not in PARAMETERS:
            raise ValueError(f"ParameterChange.parameter must be one of {PARAMETERS}, got {self.parameter!r}")


@dataclass(frozen=True)
class Judgement:
    """The judge's verdict on one executed edit.

    Attributes:
        follows_prompt: the rendered scenario does what the prompt asks.
        plausibility: ``1`` (implausible) .. ``4`` (fully plausible) as a real driving scene.
        reasons: short reasons for both answers (at least one).
        suggestions: parameter changes for the next attempt (may be empty).
    """

    follows_prompt: bool
    plausibility: int
    reasons: tuple[str, ...]
    suggestions: tuple[ParameterChange, ...] = field(default=())

    def __post_init__(self) -> None:
        if not PLAUSIBILITY_MIN <= self.plausibility <= PLAUSIBILITY_MAX:
            raise ValueError(f"Judgement.plausibility must be within {PLAUSIBILITY_MIN}..{PLAUSIBILITY_MAX}, "
                             f"got {self.plausibility}")
        object.__setattr__(self, "reasons", tuple(self.reasons))
        object.__setattr__(self, "suggestions", tuple(self.suggestions))


@runtime_checkable
class VLMClient(Protocol):
    """Proposes, translates and judges edits (module docstring)."""

    name: str

    def propose(self, request: ProposalRequest) -> list[str]:
        """Between 1 and ``request.count`` distinct edit prompts for the scene."""
        ...

    def to_command(self, prompt: str, summary: SceneSummary) -> EditProgram:
        """``prompt`` as a validated edit program (its ``prompt`` field is ``prompt``)."""
        ...

    def judge(self, request: JudgeRequest) -> Judgement:
        """The verdict on an executed edit."""
        ...


__all__ = [
    "FAILURE_KINDS",
    "PARAMETERS",
    "PLAUSIBILITY_MAX",
    "PLAUSIBILITY_MIN",
    "AgentTrajectory",
    "FailureKind",
    "JudgeRequest",
    "Judgement",
    "Parameter",
    "ParameterChange",
    "ProposalRequest",
    "SceneSummary",
    "VLMClient",
    "ValidationFailure",
]
