"""``OpenAIVLMClient``: the :class:`~simsplat_core.mining.vlm_protocol.VLMClient` over an OpenAI-compatible server.

    client = OpenAIVLMClient(OpenAIChatClient(OpenAIChatConfig.from_env()))
    prompts = client.propose(ProposalRequest(views, summary, count=5))
    program = client.to_command(prompts[0], summary)

Each call is one forced function call (:meth:`~simsplat_core.vlm.openai_chat.OpenAIChatClient.call_tool`)
whose parameters are a pydantic model's JSON Schema, and whose arguments are validated by that model:

* ``propose`` -- the views inline, the scene facts as text; :class:`~simsplat_core.mining.vlm_answers.
  ProposalAnswer` with ``maxItems = count``; repeats are dropped;
* ``to_command`` -- the facts and the prompt; the :class:`~simsplat_core.editing.commands.EditProgram` schema
  (the program's ``prompt`` is set to the prompt asked, whatever the model wrote there);
* ``judge`` -- the renders and then the BEV inline, the trajectories as sampled positions, the validation facts;
  :class:`~simsplat_core.mining.vlm_answers.JudgementAnswer`.

Timeouts, retries (HTTP and invalid answers), the concurrency limit and the key's handling are the chat client's.
"""

from __future__ import annotations

import logging
from typing import Any

from simsplat_core.editing.commands import EditProgram, edit_program_json_schema
from simsplat_core.mining.vlm_answers import (
    JudgementAnswer,
    judgement_json_schema,
    proposal_json_schema,
    validate_proposal,
)
from simsplat_core.mining.vlm_prompts import (
    COMMAND_SYSTEM,
    COMMAND_TOOL,
    JUDGE_SYSTEM,
    JUDGE_TOOL,
    PROPOSE_SYSTEM,
    PROPOSE_TOOL,
    command_text,
    judge_text,
    propose_text,
)
from simsplat_core.mining.vlm_protocol import Judgement, JudgeRequest, ProposalRequest, SceneSummary
from simsplat_core.vlm.openai_chat import OpenAIChatClient, user_message

logger = logging.getLogger(__name__)

#: Fields of :class:`EditProgram` the client fills in itself (the model's values are ignored).
_PROGRAM_OWN_FIELDS = ("prompt", "schema_version")


def _system(text: str) -> dict[str, Any]:
    return {"role": "system", "content": text}


def program_from_arguments(arguments: dict[str, Any], prompt: str) -> EditProgram:
    """A tool call's arguments as an :class:`EditProgram` for ``prompt`` (one bare command is wrapped).

    Raises:
        pydantic.ValidationError: the commands break the schema (the error names each field's path).
    """
    data = {"commands": [arguments]} if "op" in arguments else dict(arguments)
    for name in _PROGRAM_OWN_FIELDS:
        data.pop(name, None)
    return EditProgram.model_validate({**data, "prompt": prompt})


class OpenAIVLMClient:
    """Proposes, translates and judges edits with a VLM behind an OpenAI-compatible API (module docstring).

    Args:
        chat: the HTTP client (endpoint, model, timeouts, retries, concurrency).
        propose_temperature: sampling temperature of ``propose`` (some variety helps); the others use 0.
        max_tokens: answer budget of each call.
    """

    def __init__(self, chat: OpenAIChatClient, *, propose_temperature: float = 0.7, max_tokens: int = 2048) -> None:
        self.chat = chat
        self.name = f"openai-vlm:{chat.config.model}"
        self.propose_temperature = float(propose_temperature)
        self.max_tokens = int(max_tokens)

    def __repr__(self) -> str:
        return f"OpenAIVLMClient({self.chat!r})"

    def propose(self, request: ProposalRequest) -> list[str]:
        """Between 1 and ``request.count`` distinct edit prompts for the scene.

        Raises:
            VLMError: the server failed or never answered with a valid proposal.
        """
        messages = [_system(PROPOSE_SYSTEM), user_message(propose_text(request), request.views)]
        answer = self.chat.call_tool(
            messages, PROPOSE_TOOL, f"Submit up to {request.count} distinct edit prompts for this scene.",
            proposal_json_schema(request.count), lambda args: validate_proposal(args, request.count),
            max_tokens=self.max_tokens, temperature=self.propose_temperature)
        prompts = answer.unique_prompts()
        if len(prompts) < len(answer.prompts):
            logger.info("%s: dropped %d repeated prompt(s) of %s", self.name, len(answer.prompts) - len(prompts),
                        request.summary.seq_id)
        return prompts

    def to_command(self, prompt: str, summary: SceneSummary) -> EditProgram:
        """``prompt`` as a validated :class:`EditProgram` whose ``prompt`` is ``prompt``.

        Raises:
            ValueError: ``prompt`` is empty.
            VLMError: the server failed or never answered with commands that validate.
        """
        if not prompt.strip():
            raise ValueError("to_command needs a non-empty prompt")
        messages = [_system(COMMAND_SYSTEM), user_message(command_text(prompt, summary))]
        return self.chat.call_tool(
            messages, COMMAND_TOOL, "Submit the edit program (the commands, in order) that the prompt means.",
            edit_program_json_schema(), lambda args: program_from_arguments(args, prompt),
            max_tokens=self.max_tokens, temperature=0.0)

    def judge(self, request: JudgeRequest) -> Judgement:
        """The verdict on an executed edit (renders and BEV inline, trajectories as text).

        Raises:
            VLMError: the server failed or never answered with a valid judgement.
        """
        images = [*request.renders, request.bev]
        messages = [_system(JUDGE_SYSTEM), user_message(judge_text(request), images)]
        answer = self.chat.call_tool(
            messages, JUDGE_TOOL, "Submit the verdict on the edited scenario.", judgement_json_schema(),
            JudgementAnswer.model_validate, max_tokens=self.max_tokens, temperature=0.0)
        return answer.to_judgement()


__all__ = ["OpenAIVLMClient", "program_from_arguments"]
