"""Pydantic models of a VLM's JSON answers: what the function-calling schema says and what validation enforces.

* :class:`ProposalAnswer` -- ``{"prompts": ["...", ...]}``: 1..``count`` non-empty edit prompts
  (``count`` comes in the validation context and as ``maxItems`` in :func:`proposal_json_schema`);
* :class:`JudgementAnswer` -- ``{"follows_prompt": true, "plausibility": 1..4, "reasons": [...],
  "suggestions": [{"parameter": "speed", "value": "6 m/s", "reason": "..."}]}``.

Validation is strict: unknown keys are rejected, ``follows_prompt`` must be a JSON boolean and
``plausibility`` a JSON integer within 1..4, so a sloppy answer is retried rather than guessed at.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, StringConstraints, ValidationInfo, field_validator

from simsplat_core.mining.vlm_protocol import (
    PLAUSIBILITY_MAX,
    PLAUSIBILITY_MIN,
    Judgement,
    Parameter,
    ParameterChange,
)

#: Most prompts one proposal may hold whatever ``count`` asks for.
MAX_PROPOSALS = 50

PromptText = Annotated[str, StringConstraints(strip_whitespace=True, min_length=3, max_length=400)]
ReasonText = Annotated[str, StringConstraints(strip_whitespace=True, min_length=1, max_length=500)]


class _Answer(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ProposalAnswer(_Answer):
    """Candidate edit prompts for one scene."""

    prompts: list[PromptText] = Field(
        min_length=1, max_length=MAX_PROPOSALS,
        description="Distinct edit prompts, one sentence each, in plain English (e.g. 'a pedestrian jaywalks "
                    "across the road 15 m in front of the ego').")

    @field_validator("prompts")
    @classmethod
    def _at_most_count(cls, prompts: list[str], info: ValidationInfo) -> list[str]:
        count = (info.context or {}).get("count")
        if count is not None and len(prompts) > int(count):
            raise ValueError(f"at most {count} prompts were asked for, got {len(prompts)}")
        return prompts

    def unique_prompts(self) -> list[str]:
        """The prompts in order, later case-insensitive repeats dropped."""
        seen: set[str] = set()
        out = []
        for prompt in self.prompts:
            key = " ".join(prompt.lower().split())
            if key not in seen:
                seen.add(key)
                out.append(prompt)
        return out


def proposal_json_schema(count: int) -> dict[str, Any]:
    """JSON Schema of :class:`ProposalAnswer` with ``prompts.maxItems = count``."""
    schema = ProposalAnswer.model_json_schema()
    schema["properties"]["prompts"]["maxItems"] = int(count)
    return schema


def validate_proposal(data: dict[str, Any], count: int) -> ProposalAnswer:
    """``data`` as a :class:`ProposalAnswer` of at most ``count`` prompts (raises ``pydantic.ValidationError``)."""
    return ProposalAnswer.model_validate(data, context={"count": count})


class ParameterChangeAnswer(_Answer):
    """One parameter change suggested for the next attempt."""  # the model reads this (no markup)

    model_config = ConfigDict(extra="forbid", frozen=True, coerce_numbers_to_str=True)

    parameter: Parameter = Field(description="Which knob to turn: the inserted asset, the speed, the start "
                                             "time, the placement offset, the placement anchor, or other.")
    value: Annotated[str, StringConstraints(strip_whitespace=True, min_length=1, max_length=200)] = Field(
        description="The suggested value, e.g. '6 m/s', '2 s later', '5 m further ahead', 'a smaller car'.")
    reason: Annotated[str, StringConstraints(strip_whitespace=True, max_length=500)] = ""


class JudgementAnswer(_Answer):
    """The judge's verdict as JSON."""

    follows_prompt: bool = Field(strict=True, description="Does the edited scenario do what the prompt asks?")
    plausibility: int = Field(strict=True, ge=PLAUSIBILITY_MIN, le=PLAUSIBILITY_MAX,
                              description="1 = implausible, 2 = doubtful, 3 = plausible with flaws, "
                                          "4 = fully plausible as a real driving scene.")
    reasons: list[ReasonText] = Field(min_length=1, max_length=10, description="Short reasons for both answers.")
    suggestions: list[ParameterChangeAnswer] = Field(
        default_factory=list, max_length=10,
        description="Parameter changes that would fix what is wrong (empty when nothing is).")

    def to_judgement(self) -> Judgement:
        return Judgement(
            follows_prompt=self.follows_prompt, plausibility=self.plausibility, reasons=tuple(self.reasons),
            suggestions=tuple(ParameterChange(s.parameter, s.value, s.reason) for s in self.suggestions))


def judgement_json_schema() -> dict[str, Any]:
    """JSON Schema of :class:`JudgementAnswer`."""
    return JudgementAnswer.model_json_schema()


__all__ = [
    "MAX_PROPOSALS",
    "JudgementAnswer",
    "ParameterChangeAnswer",
    "ProposalAnswer",
    "judgement_json_schema",
    "proposal_json_schema",
    "validate_proposal",
]
