"""OpenAIVLMClient (propose / to_command / judge) against a local OpenAI-compatible server on 127.0.0.1."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import pytest

from simsplat_core.editing.commands import COMMAND_SCHEMA_VERSION, EditProgram, edit_program_json_schema
from simsplat_core.mining import (
    AgentTrajectory,
    Judgement,
    JudgeRequest,
    OpenAIVLMClient,
    ParameterChange,
    ProposalRequest,
    SceneSummary,
    VLMClient,
)
from simsplat_core.mining.vlm_prompts import COMMAND_TOOL, JUDGE_TOOL, PROPOSE_TOOL
from simsplat_core.vlm import ENV_API_KEY, VLMError
from tests.simsplat_core.vlm.chat_server import (
    ChatServer,
    chat_client,
    images_of,
    sequence,
    slow,
    status_reply,
    texts_of,
    tool_reply,
)

SECRET = "sk-mining-test-key-never-shown"
SUMMARY = SceneSummary("synth-000001", ("car-3: a white van, 12 m ahead in the ego lane, moving at 8 m/s",
                                        "map: crosswalk 25 m ahead"))
PROMPTS = ["A pedestrian jaywalks across the road 15 m in front of the ego.",
           "The white van ahead brakes hard before the crosswalk.",
           "Remove the white van ahead."]
STOP_VAN = {"commands": [{"op": "modify", "target": {"description": "the white van ahead"},
                          "behaviour": {"longitudinal": "brake_hard", "stop": {"before": "crosswalk"}}}]}
VERDICT = {"follows_prompt": False, "plausibility": 2,
           "reasons": ["the van stops inside the crosswalk", "the car behind drives through the van"],
           "suggestions": [{"parameter": "start_time", "value": "1 s earlier", "reason": "stop before the crosswalk"},
                           {"parameter": "speed", "value": 6, "reason": "a gentler stop"}]}


def _image(rgb: tuple[int, int, int], shape: tuple[int, int] = (8, 12)) -> np.ndarray:
    return np.broadcast_to(np.array(rgb, np.uint8), (*shape, 3)).copy()


def _vlm(server: ChatServer, sleeps: list[float] | None = None, **kw: Any) -> OpenAIVLMClient:
    return OpenAIVLMClient(chat_client(server, sleeps, **kw))


def _judge_request() -> JudgeRequest:
    van = np.stack([np.linspace(12.0, 24.0, 31), np.zeros(31)], axis=1)  # [31, 2]: 12 m in 3 s
    walker = np.full((31, 2), np.nan)
    walker[10:] = np.stack([np.full(21, 30.0), np.linspace(-5.0, 5.0, 21)], axis=1)  # appears at 1 s
    return JudgeRequest(
        prompt=PROMPTS[1], renders=[_image((255, 0, 0)), _image((0, 255, 0))], bev=_image((0, 0, 255), (16, 16)),
        trajectories=[AgentTrajectory("ped-7", "pedestrian", "refined", walker),
                      AgentTrajectory("car-3", "vehicle", "edited", van, is_target=True)],
        validation=("collision: car-3 with car-5 at 2.4 s", "off-road: none"), dt_s=0.1,
        command_json='{"commands": [{"op": "modify"}]}')


def test_the_client_is_a_vlm_client(server: ChatServer) -> None:
    vlm = _vlm(server)
    assert isinstance(vlm, VLMClient) and vlm.name == "openai-vlm:test-vlm"


def test_propose_sends_the_views_and_facts_and_returns_the_prompts(server: ChatServer) -> None:
    server.reply = tool_reply(PROPOSE_TOOL, {"prompts": [*PROMPTS, "  remove the WHITE van  ahead. "]})
    views = [_image((255, 0, 0)), _image((0, 0, 255))]
    prompts = _vlm(server).propose(ProposalRequest(views, SUMMARY, count=4))
    assert prompts == PROMPTS  # stripped, and the case/space-insensitive repeat dropped
    (req,) = server.requests
    body = req["body"]
    assert body["tool_choice"]["function"]["name"] == PROPOSE_TOOL
    params = body["tools"][0]["function"]["parameters"]
    assert params["properties"]["prompts"]["maxItems"] == 4
    assert body["messages"][0]["role"] == "system" and "safety-critical" in body["messages"][0]["content"]
    user = texts_of(body, role="user")[0]
    assert "synth-000001" in user and "car-3: a white van" in user and "up to 4" in user
    sent = images_of(body)
    assert len(sent) == 2 and (sent[0] == [255, 0, 0]).all() and (sent[1] == [0, 0, 255]).all()


def test_propose_retries_too_many_prompts_then_fails(server: ChatServer) -> None:
    server.reply = tool_reply(PROPOSE_TOOL, {"prompts": PROMPTS})
    with pytest.raises(VLMError, match=r"propose_edits.*prompts: Value error, at most 2 prompts"):
        _vlm(server, max_retries=1).propose(ProposalRequest([_image((9, 9, 9))], SUMMARY, count=2))
    assert len(server.requests) == 2


def test_to_command_returns_a_validated_program_and_sends_the_schema(server: ChatServer) -> None:
    server.reply = tool_reply(COMMAND_TOOL, {**STOP_VAN, "prompt": "something else", "schema_version": "v0"})
    program = _vlm(server).to_command(PROMPTS[1], SUMMARY)
    assert isinstance(program, EditProgram)
    assert program.prompt == PROMPTS[1] and program.schema_version == COMMAND_SCHEMA_VERSION
    (command,) = program.commands
    assert command.op == "modify" and command.target is not None
    assert command.target.description == "the white van ahead"
    assert command.behaviour is not None and command.behaviour.stop is not None
    assert command.behaviour.stop.before == "crosswalk"
    body = server.requests[0]["body"]
    assert body["tools"][0]["function"]["name"] == COMMAND_TOOL
    assert body["tools"][0]["function"]["parameters"] == edit_program_json_schema()
    assert body["tool_choice"] == {"type": "function", "function": {"name": COMMAND_TOOL}}
    user = texts_of(body, role="user")[0]
    assert PROMPTS[1] in user and "crosswalk 25 m ahead" in user


def test_to_command_accepts_one_bare_command(server: ChatServer) -> None:
    server.reply = tool_reply(COMMAND_TOOL, {"op": "remove", "target": {"description": "the white van"}})
    program = _vlm(server).to_command(PROMPTS[2], SUMMARY)
    assert [c.op for c in program.commands] == ["remove"]


def test_to_command_retries_malformed_json_and_tells_the_model(server: ChatServer) -> None:
    server.reply = sequence(tool_reply(COMMAND_TOOL, '{"commands": [{"op": "remove",'),
                            tool_reply(COMMAND_TOOL, STOP_VAN))
    sleeps: list[float] = []
    program = _vlm(server, sleeps, backoff_s=0.5).to_command(PROMPTS[1], SUMMARY)
    assert program.commands[0].op == "modify" and sleeps == [0.5]
    retry = texts_of(server.requests[1]["body"], role="user")[-1]
    assert "not valid JSON" in retry and COMMAND_TOOL in retry


@pytest.mark.parametrize(("command", "field"), [
    ({"op": "explode", "target": {"description": "the van"}}, "commands.0.op"),
    ({"op": "insert"}, "op 'insert' needs asset"),
    ({"op": "modify", "target": {"description": "the van"}, "behaviour": {"speed": {"value": 500}}},
     "commands.0.behaviour.speed"),
    ({"op": "remove", "target": {"description": "ego"}}, "the ego vehicle cannot be edited"),
])
def test_schema_violating_commands_are_retried_then_fail_naming_the_field(server: ChatServer,
                                                                        command: dict[str, Any], field: str) -> None:
    server.reply = tool_reply(COMMAND_TOOL, {"commands": [command]})
    with pytest.raises(VLMError) as err:
        _vlm(server, max_retries=2).to_command("Make the van explode.", SUMMARY)
    assert field in str(err.value) and COMMAND_TOOL in str(err.value) and server.base_url in str(err.value)
    assert len(server.requests) == 3
    assert all(field in t for t in texts_of(server.requests[-1]["body"], role="user")[1:])


def test_a_schema_violation_then_a_good_command_succeeds(server: ChatServer) -> None:
    server.reply = sequence(tool_reply(COMMAND_TOOL, {"commands": [{"op": "explode"}]}),
                            tool_reply(COMMAND_TOOL, STOP_VAN))
    assert _vlm(server, max_retries=1).to_command(PROMPTS[1], SUMMARY).commands[0].op == "modify"


def test_judge_sends_renders_then_bev_and_the_trajectories_and_parses_the_verdict(server: ChatServer) -> None:
    server.reply = tool_reply(JUDGE_TOOL, VERDICT)
    verdict = _vlm(server).judge(_judge_request())
    assert verdict == Judgement(
        follows_prompt=False, plausibility=2,
        reasons=("the van stops inside the crosswalk", "the car behind drives through the van"),
        suggestions=(ParameterChange("start_time", "1 s earlier", "stop before the crosswalk"),
                     ParameterChange("speed", "6", "a gentler stop")))
    body = server.requests[0]["body"]
    assert body["tool_choice"]["function"]["name"] == JUDGE_TOOL
    params = body["tools"][0]["function"]["parameters"]
    assert params["properties"]["plausibility"]["maximum"] == 4
    sent = images_of(body)
    assert [tuple(img[0, 0]) for img in sent] == [(255, 0, 0), (0, 255, 0), (0, 0, 255)]  # renders, then the BEV
    assert sent[2].shape == (16, 16, 3)
    text = texts_of(body, role="user")[0]
    lines = text.splitlines()
    van = next(line for line in lines if line.startswith("- car-3"))
    walker = next(line for line in lines if line.startswith("- ped-7"))
    assert lines.index(van) < lines.index(walker)  # the target first
    assert "[target] vehicle, edited" in van and "t=0.0s (12.0, 0.0)" in van and "t=3.0s (24.0, 0.0)" in van
    assert "travelled 12.0 m, mean speed 4.0 m/s" in van
    assert "t=1.0s (30.0, -5.0)" in walker and "[target]" not in walker
    assert "collision: car-3 with car-5 at 2.4 s" in text and PROMPTS[1] in text and '"op": "modify"' in text


@pytest.mark.parametrize(("verdict", "field"), [
    ({**VERDICT, "plausibility": 7}, "plausibility"),
    ({**VERDICT, "follows_prompt": "yes"}, "follows_prompt"),
    ({**VERDICT, "reasons": []}, "reasons"),
    ({**VERDICT, "suggestions": [{"parameter": "colour", "value": "red"}]}, "suggestions.0.parameter"),
])
def test_invalid_verdicts_are_retried_then_fail_never_returned(server: ChatServer, verdict: dict[str, Any],
                                                               field: str) -> None:
    server.reply = tool_reply(JUDGE_TOOL, verdict)
    with pytest.raises(VLMError, match=rf"{JUDGE_TOOL}.*{field}"):
        _vlm(server, max_retries=1).judge(_judge_request())
    assert len(server.requests) == 2


def test_rate_limit_then_success_backs_off(server: ChatServer) -> None:
    server.reply = sequence(status_reply(429, "rate limited"), tool_reply(JUDGE_TOOL, VERDICT))
    sleeps: list[float] = []
    assert _vlm(server, sleeps, backoff_s=0.3).judge(_judge_request()).plausibility == 2
    assert len(server.requests) == 2 and sleeps == [0.3]


def test_server_errors_forever_fail_after_max_retries_plus_one(server: ChatServer) -> None:
    server.reply = status_reply(500, "internal error")
    with pytest.raises(VLMError, match=r"HTTP 500 after 4 attempt\(s\)"):
        _vlm(server, max_retries=3).to_command(PROMPTS[0], SUMMARY)
    assert len(server.requests) == 4


def test_a_slow_server_fails_after_the_retries(server: ChatServer) -> None:
    server.reply = slow(0.5, tool_reply(PROPOSE_TOOL, {"prompts": PROMPTS}))
    with pytest.raises(VLMError, match="ReadTimeout"):
        _vlm(server, max_retries=0, timeout_s=0.2).propose(ProposalRequest([_image((1, 2, 3))], SUMMARY))
    assert len(server.requests) == 1


def test_the_key_is_sent_as_bearer_but_never_logged_or_shown(server: ChatServer, monkeypatch: pytest.MonkeyPatch,
                                                             caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.setenv(ENV_API_KEY, SECRET)
    server.reply = sequence(status_reply(503, f"busy (key {SECRET})"),
                            tool_reply(COMMAND_TOOL, {"commands": [{"op": "explode", "note": SECRET}]}))
    vlm = _vlm(server, max_retries=1)
    with caplog.at_level(logging.DEBUG), pytest.raises(VLMError) as err:
        vlm.to_command(PROMPTS[0], SUMMARY)
    assert [r["headers"]["Authorization"] for r in server.requests] == [f"Bearer {SECRET}"] * 3
    assert "commands.0.op" in str(err.value)
    for shown in (str(err.value), caplog.text, repr(vlm), repr(vlm.chat.config)):
        assert SECRET not in shown
    assert "***" in caplog.text
