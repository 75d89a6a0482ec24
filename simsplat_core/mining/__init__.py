"""Scenario mining: the ``VLMClient`` protocol (propose edit prompts, turn them into commands, judge the
rendered result), its OpenAI-compatible HTTP client and the rule-based offline client, the scene facts both read,
the judge request built from an executed edit, and the loop that proposes, edits, judges and retries
(``mine_sequence``: one ``AttemptRecord`` per attempt, the accepted ones marked for export)."""

from simsplat_core.mining.adjust import Adjustment, adjust_program
from simsplat_core.mining.attempts import AttemptRecord, MiningResult, attempt_rows
from simsplat_core.mining.judge_input import judge_request_from_edit, visible_pixels_of
from simsplat_core.mining.judge_views import JudgeViews, judge_views, proposal_views
from simsplat_core.mining.loop import MiningConfig, default_client, mine_sequence
from simsplat_core.mining.openai_vlm import OpenAIVLMClient
from simsplat_core.mining.rule_client import ProposalRejected, RuleBasedVLMClient
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES, Proposal, propose_edits
from simsplat_core.mining.scene_fact_records import AgentFacts, AssetFacts, RoadFacts, SceneFacts
from simsplat_core.mining.scene_facts import scene_facts, summary
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
    "Adjustment",
    "AgentFacts",
    "AgentTrajectory",
    "AssetFacts",
    "AttemptRecord",
    "JudgeRequest",
    "Judgement",
    "JudgeViews",
    "MiningConfig",
    "MiningResult",
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
    "adjust_program",
    "attempt_rows",
    "default_client",
    "judge_request_from_edit",
    "judge_views",
    "mine_sequence",
    "propose_edits",
    "proposal_views",
    "scene_facts",
    "summary",
    "visible_pixels_of",
]
