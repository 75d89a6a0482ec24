"""Scenario mining: the ``VLMClient`` protocol (propose edit prompts, turn them into commands, judge the
rendered result) and its OpenAI-compatible HTTP client."""

from simsplat_core.mining.openai_vlm import OpenAIVLMClient
from simsplat_core.mining.vlm_protocol import (
    PARAMETERS,
    AgentTrajectory,
    Judgement,
    JudgeRequest,
    Parameter,
    ParameterChange,
    ProposalRequest,
    SceneSummary,
    VLMClient,
)

__all__ = [
    "PARAMETERS",
    "AgentTrajectory",
    "JudgeRequest",
    "Judgement",
    "OpenAIVLMClient",
    "Parameter",
    "ParameterChange",
    "ProposalRequest",
    "SceneSummary",
    "VLMClient",
]
