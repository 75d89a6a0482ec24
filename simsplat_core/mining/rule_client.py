"""``RuleBasedVLMClient``: the offline :class:`~simsplat_core.mining.vlm_protocol.VLMClient`, from grounded facts
and explicit checks instead of a model.

    client = RuleBasedVLMClient(seed=0)
    summary = summary(scene_facts(ctx))                        # mining.scene_facts: text + structured facts
    prompts = client.propose(ProposalRequest(views, summary, count=6))
    program = client.to_command(prompts[0], summary)           # the command parser; ProposalRejected if refused
    verdict = client.judge(judge_request_from_edit(edited, renders, bev))

* ``propose`` reads ``request.summary.facts`` (or ``facts_of(summary)``), never the images, and returns
  ``mining.rule_proposals.propose_edits``: feasible prompts over the six edit categories, safety-critical ones
  first, in varied wording, the same for the same seed and facts;
* ``to_command`` is the project's parser (``editing.parse.prompt.parse_prompt``); a refusal is re-raised as
  :class:`ProposalRejected` (an ``EditRefused`` naming the prompt);
* ``judge`` is ``mining.rule_judge.judge_edit``: explicit checks and concrete parameter changes.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from simsplat_core.editing.commands import EditProgram
from simsplat_core.editing.parse.prompt import parse_prompt
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.text import TextEncoder
from simsplat_core.mining.rule_judge import JudgeConfig, judge_edit
from simsplat_core.mining.rule_proposals import Proposal, propose_edits
from simsplat_core.mining.scene_fact_records import SceneFacts
from simsplat_core.mining.vlm_protocol import Judgement, JudgeRequest, ProposalRequest, SceneSummary

logger = logging.getLogger(__name__)


class ProposalRejected(EditRefused):
    """A prompt the command parser refuses; ``reason`` is the parser's (``EditRefused.reason``).

    Attributes:
        prompt: the refused prompt.
    """

    def __init__(self, prompt: str, message: str, *, reason: str) -> None:
        super().__init__(f"{prompt!r} cannot be turned into commands: {message}", reason=reason)
        self.prompt = prompt


class RuleBasedVLMClient:
    """The rule-based offline client (module docstring).

    Args:
        seed: seeds the proposals (the same seed and facts give the same prompts).
        facts_of: facts of a summary that carries none (``SceneSummary.facts`` is ``None``).
        encoder: text encoder for words the parser's rules do not know (default: loaded only when needed).
        judge_config: the judge's thresholds.
        category_offset: where this sequence starts in the run's order of edit categories
            (``rule_proposals.propose_edits``; ``None``: the scene's own seeded order).
        categories: the edit categories to propose (``rule_proposals.EDIT_CATEGORIES``; empty: all).
    """

    name = "rule-based/1"

    def __init__(self, seed: int = 0, facts_of: Callable[[SceneSummary], SceneFacts] | None = None, *,
                 encoder: TextEncoder | None = None, judge_config: JudgeConfig | None = None,
                 category_offset: int | None = None, categories: tuple[str, ...] = ()) -> None:
        self.seed = int(seed)
        self.category_offset = category_offset
        self.categories = tuple(categories)
        self.facts_of = facts_of
        self.encoder = encoder
        self.judge_config = judge_config or JudgeConfig()

    def __repr__(self) -> str:
        return f"RuleBasedVLMClient(seed={self.seed})"

    def facts(self, summary: SceneSummary) -> SceneFacts:
        """The structured facts of ``summary``.

        Raises:
            ValueError: the summary carries none and no ``facts_of`` was given.
        """
        if summary.facts is not None:
            return summary.facts
        if self.facts_of is not None:
            return self.facts_of(summary)
        raise ValueError(f"{summary.seq_id}: the rule-based client proposes from structured facts: build the summary "
                         "with mining.scene_facts.summary(scene_facts(ctx)), or give facts_of")

    def proposals(self, summary: SceneSummary, count: int) -> list[Proposal]:
        """Up to ``count`` proposals with their category, kind and target (what :meth:`propose` words).

        Raises:
            ValueError: no facts (see :meth:`facts`), or no feasible edit in the scene.
        """
        found = propose_edits(self.facts(summary), count, self.seed, self.category_offset, self.categories)
        if not found:
            raise ValueError(f"{summary.seq_id}: no feasible edit in this scene (no nameable objects, no lane and no "
                             "assets)")
        return found

    def propose(self, request: ProposalRequest) -> list[str]:
        """Between 1 and ``request.count`` distinct edit prompts from the summary's facts (the views are not read).

        Raises:
            ValueError: see :meth:`proposals`.
        """
        return [p.prompt for p in self.proposals(request.summary, request.count)]

    def to_command(self, prompt: str, summary: SceneSummary) -> EditProgram:
        """``prompt`` parsed by the command parser (its ``prompt`` field is ``prompt``).

        Raises:
            ProposalRejected: the parser refuses the prompt.
        """
        try:
            program = parse_prompt(prompt, encoder=self.encoder)
        except EditRefused as exc:
            logger.info("%s: %r refused (%s): %s", summary.seq_id, prompt, exc.reason, exc)
            raise ProposalRejected(prompt, str(exc), reason=exc.reason) from exc
        return program if program.prompt == prompt else program.model_copy(update={"prompt": prompt})

    def judge(self, request: JudgeRequest) -> Judgement:
        """The verdict from explicit checks (``mining.rule_judge``)."""
        return judge_edit(request, self.judge_config)


__all__ = ["ProposalRejected", "RuleBasedVLMClient"]
