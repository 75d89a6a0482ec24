"""OpenAIChatClient.call_tool against a local server on 127.0.0.1, and the tool-answer parsing helpers."""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

import pytest
from pydantic import BaseModel, ConfigDict, Field

from simsplat_core.vlm import (
    ENV_API_KEY,
    MAX_RETRY_AFTER_S,
    OpenAIChatClient,
    OpenAIChatConfig,
    ToolAnswerError,
    VLMError,
    tool_arguments,
    tool_request_fields,
    user_message,
)
from tests.simsplat_core.vlm.chat_server import (
    ChatServer,
    chat_client,
    sequence,
    slow,
    status_reply,
    text_reply,
    texts_of,
    tool_reply,
)

SECRET = "sk-test-0123456789-do-not-log"
TOOL = "report_car"


class CarReport(BaseModel):
    model_config = ConfigDict(extra="forbid")

    colour: str = Field(min_length=1)
    wheels: int = Field(ge=3, le=18)


GOOD = {"colour": "red", "wheels": 4}
GOOD_REPORT = CarReport(colour="red", wheels=4)




def _call(client: OpenAIChatClient) -> CarReport:
    return client.call_tool([user_message("Describe the car.")], TOOL, "Report the car.",
                            CarReport.model_json_schema(), CarReport.model_validate)


def test_a_good_answer_is_validated_and_the_request_forces_the_tool(server: ChatServer) -> None:
    server.reply = tool_reply(TOOL, GOOD)
    report = chat_client(server).call_tool([user_message("Describe the car.")], TOOL, "Report the car.",
                                       CarReport.model_json_schema(), CarReport.model_validate, max_tokens=99)
    assert report == CarReport(colour="red", wheels=4)
    (req,) = server.requests
    body = req["body"]
    assert body["tools"] == [{"type": "function", "function": {"name": TOOL, "description": "Report the car.",
                                                               "parameters": CarReport.model_json_schema()}}]
    assert body["tool_choice"] == {"type": "function", "function": {"name": TOOL}}
    assert body["max_tokens"] == 99 and body["model"] == "test-vlm"
    assert body["messages"] == [{"role": "user", "content": "Describe the car."}]


def test_a_json_object_in_the_content_is_accepted_from_servers_without_tool_calling(server: ChatServer) -> None:
    server.reply = text_reply('```json\n{"colour": "blue", "wheels": 6}\n```')
    assert _call(chat_client(server)) == CarReport(colour="blue", wheels=6)


def test_malformed_json_is_retried_and_the_model_is_told_what_was_wrong(server: ChatServer) -> None:
    server.reply = sequence(tool_reply(TOOL, '{"colour": "red", "wheels": 4'), tool_reply(TOOL, GOOD))
    sleeps: list[float] = []
    report = _call(chat_client(server, sleeps, backoff_s=0.25, max_retries=2))
    assert report.colour == "red"
    assert len(server.requests) == 2 and sleeps == [0.25]
    first, second = (r["body"]["messages"] for r in server.requests)
    assert len(first) == 1 and second[:1] == first
    assert second[1] == {"role": "assistant", "content": '{"colour": "red", "wheels": 4'}
    assert second[2]["role"] == "user"
    assert "not valid JSON" in second[2]["content"] and TOOL in second[2]["content"]


def test_schema_violations_are_retried_then_fail_naming_the_field(server: ChatServer) -> None:
    server.reply = tool_reply(TOOL, {"colour": "red", "wheels": 40})
    with pytest.raises(VLMError) as err:
        _call(chat_client(server, max_retries=2))
    message = str(err.value)
    assert server.base_url in message and f"tool {TOOL}" in message and "after 3 attempt(s)" in message
    assert "wheels" in message and "less than or equal to 18" in message
    assert len(server.requests) == 3
    retry_turns = texts_of(server.requests[-1]["body"], role="user")[1:]
    assert len(retry_turns) == 2 and all("wheels" in t for t in retry_turns)


def test_invalid_then_valid_returns_the_valid_answer(server: ChatServer) -> None:
    server.reply = sequence(tool_reply(TOOL, {"colour": "red", "wheels": 4, "doors": 2}), tool_reply(TOOL, GOOD))
    assert _call(chat_client(server, max_retries=1)) == GOOD_REPORT
    assert "doors" in texts_of(server.requests[1]["body"], role="user")[-1]


def test_no_tool_call_and_the_wrong_tool_are_malformed_answers(server: ChatServer) -> None:
    server.reply = sequence(text_reply("It is a red car."), tool_reply("other_tool", GOOD), tool_reply(TOOL, GOOD))
    assert _call(chat_client(server, max_retries=2)) == GOOD_REPORT
    turns = texts_of(server.requests[2]["body"], role="user")
    assert "no JSON object" in turns[1] and "called other_tool instead of report_car" in turns[2]


def test_server_errors_are_retried_with_back_off_and_retry_after(server: ChatServer) -> None:
    server.reply = sequence(status_reply(429, "slow down"), status_reply(429, "slow down", {"Retry-After": "7"}),
                            status_reply(503, "busy", {"Retry-After": "9"}), tool_reply(TOOL, GOOD))
    sleeps: list[float] = []
    assert _call(chat_client(server, sleeps, backoff_s=0.5, max_retries=3)) == GOOD_REPORT
    assert len(server.requests) == 4
    assert sleeps == [0.5, 7.0, 2.0]  # doubling back-off, stretched by a 429's Retry-After (not a 503's)


def test_retry_after_is_capped(server: ChatServer) -> None:
    server.reply = sequence(status_reply(429, "later", {"Retry-After": "86400"}), tool_reply(TOOL, GOOD))
    sleeps: list[float] = []
    _call(chat_client(server, sleeps, backoff_s=0.1, max_retries=1))
    assert sleeps == [MAX_RETRY_AFTER_S]


def test_persistent_server_errors_fail_after_max_retries_plus_one_requests(server: ChatServer) -> None:
    server.reply = status_reply(500, "boom")
    with pytest.raises(VLMError, match=r"HTTP 500 after 3 attempt\(s\): boom"):
        _call(chat_client(server, max_retries=2))
    assert len(server.requests) == 3


def test_client_errors_are_not_retried(server: ChatServer) -> None:
    server.reply = status_reply(400, "tools are not supported by this model")
    with pytest.raises(VLMError, match="HTTP 400 after 1 attempt"):
        _call(chat_client(server, max_retries=3))
    assert len(server.requests) == 1


def test_a_slow_server_times_out_and_is_retried(server: ChatServer) -> None:
    server.reply = sequence(slow(0.5, tool_reply(TOOL, GOOD)), tool_reply(TOOL, GOOD))
    assert _call(chat_client(server, max_retries=1, timeout_s=0.2)) == GOOD_REPORT
    assert len(server.requests) == 2


def test_a_server_slower_than_the_timeout_fails_after_the_retries(server: ChatServer) -> None:
    server.reply = slow(0.5, tool_reply(TOOL, GOOD))
    with pytest.raises(VLMError, match=r"request failed after 2 attempt\(s\): ReadTimeout"):
        _call(chat_client(server, max_retries=1, timeout_s=0.2))
    assert len(server.requests) == 2


def test_concurrency_is_limited_per_client_across_threads() -> None:
    server = ChatServer().start()
    try:
        window = {"until": float("inf")}

        def held(body: dict[str, Any]) -> tuple[Any, ...]:
            # hold every request until a third one is in flight (the limit is broken) or 0.3 s after the
            # first request: a client that ignored its limit would have all six in flight by then
            window["until"] = min(window["until"], time.monotonic() + 0.3)
            server.wait_for_in_flight(3, timeout_s=max(0.0, window["until"] - time.monotonic()))
            return tool_reply(TOOL, GOOD)(body)

        server.reply = held
        client = chat_client(server, max_concurrency=2)
        results: list[CarReport] = []
        threads = [threading.Thread(target=lambda: results.append(_call(client))) for _ in range(6)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10.0)
        assert len(results) == 6 and len(server.requests) == 6
        assert server.max_in_flight == 2
    finally:
        server.stop()


def test_the_key_is_sent_but_never_logged_or_shown(server: ChatServer, monkeypatch: pytest.MonkeyPatch,
                                                   caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.setenv(ENV_API_KEY, SECRET)
    # a careless server echoes the key in its errors and the model in its answer
    server.reply = sequence(status_reply(503, f"overloaded, key {SECRET}"),
                            tool_reply(TOOL, {"colour": SECRET, "wheels": 99}),
                            status_reply(401, f"invalid api key {SECRET}"))
    client = chat_client(server, max_retries=2)
    with caplog.at_level(logging.DEBUG), pytest.raises(VLMError) as err:
        _call(client)
    assert all(r["headers"]["Authorization"] == f"Bearer {SECRET}" for r in server.requests)
    assert len(server.requests) == 3 and "HTTP 401" in str(err.value) and "***" in str(err.value)
    assert caplog.text and "***" in caplog.text
    for shown in (str(err.value), caplog.text, repr(client), repr(client.config)):
        assert SECRET not in shown


def test_the_key_is_masked_in_a_final_tool_error(server: ChatServer, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(ENV_API_KEY, SECRET)
    server.reply = tool_reply(TOOL, f'{{"colour": "{SECRET}", "wheels": 99')
    with pytest.raises(VLMError) as err:
        _call(chat_client(server, max_retries=0))
    assert "not valid JSON" in str(err.value) and SECRET not in str(err.value)


def test_complete_still_reads_text_answers(server: ChatServer) -> None:
    server.reply = sequence(status_reply(502, "gateway"), text_reply(" a white van "))
    assert chat_client(server, max_retries=1).complete([user_message("x")]) == "a white van"
    assert "tools" not in server.requests[-1]["body"]


def test_max_concurrency_is_validated() -> None:
    with pytest.raises(ValueError, match="max_concurrency"):
        OpenAIChatConfig(base_url="http://127.0.0.1:1/v1", model="m", max_concurrency=0)


# -- parsing helpers (no server) --------------------------------------------------------------------------------


def _answer(message: dict[str, Any], finish_reason: str = "stop") -> dict[str, Any]:
    return {"choices": [{"message": message, "finish_reason": finish_reason}]}


def _call_message(name: str, arguments: Any) -> dict[str, Any]:
    return {"tool_calls": [{"type": "function", "function": {"name": name, "arguments": arguments}}]}


@pytest.mark.parametrize("message", [
    _call_message(TOOL, '{"a": 1}'),
    _call_message(TOOL, {"a": 1}),
    {"tool_calls": [{"function": {"name": "noise", "arguments": "{}"}}, {"function": {"name": TOOL,
                                                                                      "arguments": '{"a": 1}'}}]},
    {"content": '{"a": 1}'},
    {"content": '  ```\n{"a": 1}\n```  '},
    {"content": [{"type": "text", "text": '{"a": '}, {"type": "text", "text": "1}"}]},
    {"content": f'{{"name": "{TOOL}", "arguments": {{"a": 1}}}}'},
    {"content": f'{{"name": "{TOOL}", "parameters": "{{\\"a\\": 1}}"}}'},
])
def test_tool_arguments_are_read_from_every_answer_shape(message: dict[str, Any]) -> None:
    assert tool_arguments(_answer(message), TOOL) == {"a": 1}


@pytest.mark.parametrize(("payload", "expected"), [
    ({"choices": []}, "no choices[0].message"),
    (_answer(_call_message(TOOL, "[1, 2]")), "must be a JSON object, got list"),
    (_answer(_call_message(TOOL, 7)), "must be a JSON object or a JSON string"),
    (_answer({"content": None}), "no call of report_car and no content"),
    (_answer({"content": "{oops"}), "not valid JSON"),
    (_answer(_call_message(TOOL, '{"a": '), finish_reason="length"), "cut off at max_tokens"),
])
def test_malformed_answers_say_what_is_wrong(payload: Any, expected: str) -> None:
    with pytest.raises(ToolAnswerError, match=expected.replace("[", r"\[").replace("(", r"\(")):
        tool_arguments(payload, TOOL)


def test_tool_names_are_checked() -> None:
    with pytest.raises(ValueError, match="tool names"):
        tool_request_fields("report car", "x", {})
