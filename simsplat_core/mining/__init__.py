"""Scenario mining: the ``VLMClient`` protocol (propose edit prompts, turn them into commands, judge the
rendered result), its OpenAI-compatible HTTP client and the rule-based offline client, the scene facts both read
and the judge request built from an executed edit."""

from simsplat_core.mining.judge_input import judge_request_from_edit, visible_pixels_of
from simsplat_core.mining.openai_vlm import OpenAIVLMClient
from simsplat_core.mining.rule_client import ProposalRejected, RuleBasedVLMClient
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES, Proposal, propose_edits
from simsplat_core.mining.scene_facts import AgentFacts, AssetFacts, RoadFacts, SceneFacts, scene_facts, summary
from simsplat_core.mining.vlm_protocol import (
    PARAMETERS,
    AgentTrajectory,
    Judgement,
    JudgeRequest,
    Parameter,
    ParameterChange,
    ProposalRequest,
    SceneSummary,
    ValidationFailure,
    VLMClient,
)

__all__ = [
    "EDIT_CATEGORIES",
    "PARAMETERS",
    "AgentFacts",
    "AgentTrajectory",
    "AssetFacts",
    "JudgeRequest",
    "Judgement",
    "OpenAIVLMClient",
    "Parameter",
    "ParameterChange",
    "Proposal",
    "ProposalRejected",
    "ProposalRequest",
    "RoadFacts",
    "RuleBasedVLMClient",
    "SceneFacts",
    "SceneSummary",
    "VLMClient",
    "ValidationFailure",
    "judge_request_from_edit",
    "propose_edits",
    "scene_facts",
    "summary",
    "visible_pixels_of",
]
