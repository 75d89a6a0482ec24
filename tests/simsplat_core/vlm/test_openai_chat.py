"""OpenAIChatClient against a real HTTP server on 127.0.0.1."""

from __future__ import annotations

import logging
import socket
from collections.abc import Iterator

import httpx
import numpy as np
import pytest

from simsplat_core.vlm import (
    ENV_API_KEY,
    ENV_MODEL,
    ENV_URL,
    OpenAIChatClient,
    OpenAIChatConfig,
    VLMError,
    VLMUnreachableError,
    user_message,
)
from tests.simsplat_core.vlm.chat_server import ChatServer, images_of, text_reply

SECRET = "sk-test-0123456789-do-not-log"


@pytest.fixture()
def server() -> Iterator[ChatServer]:
    srv = ChatServer().start()
    yield srv
    srv.stop()


def _client(server: ChatServer, **kw) -> OpenAIChatClient:
    return OpenAIChatClient(OpenAIChatConfig(base_url=server.base_url, model="test-vlm", backoff_s=0.0, **kw))


def test_request_follows_the_protocol_and_carries_images(server: ChatServer, monkeypatch) -> None:
    monkeypatch.setenv(ENV_API_KEY, SECRET)
    server.reply = text_reply("  A red SUV.  ")
    image = np.zeros((6, 10, 3), np.float32)
    image[:, :5, 0] = 1.0  # left half red
    text = _client(server).complete([user_message("What is it?", [image])], max_tokens=12)
    assert text == "A red SUV."
    (req,) = server.requests
    assert req["path"] == "/v1/chat/completions"
    assert req["headers"]["Authorization"] == f"Bearer {SECRET}"
    body = req["body"]
    assert body["model"] == "test-vlm" and body["max_tokens"] == 12 and body["temperature"] == 0.0
    parts = body["messages"][0]["content"]
    assert body["messages"][0]["role"] == "user" and parts[0] == {"type": "text", "text": "What is it?"}
    (sent,) = images_of(body)
    assert sent.shape == (6, 10, 3)
    assert (sent[:, :5] == [255, 0, 0]).all()
    assert (sent[:, 5:] == 0).all()


def test_no_key_no_authorization_header(server: ChatServer, monkeypatch) -> None:
    monkeypatch.delenv(ENV_API_KEY, raising=False)
    _client(server).complete([user_message("hi")])
    assert "Authorization" not in server.requests[0]["headers"]
    assert server.requests[0]["body"]["messages"] == [{"role": "user", "content": "hi"}]


def test_content_parts_are_joined(server: ChatServer) -> None:
    server.reply = lambda body: (200, {"choices": [{"message": {"content": [{"type": "text", "text": "a blue "},
                                                                           {"type": "text", "text": "van"}]}}]})
    assert _client(server).complete([user_message("x")]) == "a blue van"


def test_server_errors_are_retried(server: ChatServer) -> None:
    answers = iter([(503, {"error": {"message": "overloaded"}}), (429, {"error": "slow down"}),
                    (200, {"choices": [{"message": {"content": "a white van"}}]})])
    server.reply = lambda body: next(answers)
    assert _client(server, max_retries=2).complete([user_message("x")]) == "a white van"
    assert len(server.requests) == 3


def test_client_errors_fail_at_once_with_status_and_message_but_not_the_key(server: ChatServer, monkeypatch,
                                                                           caplog) -> None:
    monkeypatch.setenv(ENV_API_KEY, SECRET)
    server.reply = lambda body: (400, {"error": {"message": "model 'test-vlm' does not take images"}})
    with caplog.at_level(logging.DEBUG), pytest.raises(VLMError) as err:
        _client(server, max_retries=3).complete([user_message("x")])
    message = str(err.value)
    assert server.base_url in message and "HTTP 400" in message and "does not take images" in message
    assert len(server.requests) == 1
    assert SECRET not in message and SECRET not in caplog.text and SECRET not in repr(_client(server))


def test_retries_run_out_on_persistent_server_errors(server: ChatServer) -> None:
    server.reply = lambda body: (500, {"error": {"message": "boom"}})
    with pytest.raises(VLMError, match=r"HTTP 500 after 3 attempt\(s\): boom"):
        _client(server, max_retries=2).complete([user_message("x")])
    assert len(server.requests) == 3


def test_unreachable_server_names_the_url() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # closed again when the block ends: nothing listens there
    client = OpenAIChatClient(OpenAIChatConfig(base_url=f"http://127.0.0.1:{port}/v1", model="m", max_retries=1,
                                               backoff_s=0.0, timeout_s=2.0))
    with pytest.raises(VLMUnreachableError, match=rf"127\.0\.0\.1:{port}/v1/chat/completions: request failed after 2"):
        client.complete([user_message("x")])


def test_a_host_that_never_answers_fails_after_the_connect_timeout_per_attempt() -> None:
    timeouts: list[object] = []
    waits: list[float] = []

    def never_connects(request: httpx.Request) -> httpx.Response:
        timeouts.append(request.extensions["timeout"])
        raise httpx.ConnectTimeout("timed out", request=request)

    config = OpenAIChatConfig(base_url="http://10.255.255.1/v1", model="m", max_retries=2, backoff_s=0.5,
                              timeout_s=60.0, connect_timeout_s=3.0)
    client = OpenAIChatClient(config, httpx.MockTransport(never_connects), sleep=waits.append)
    with pytest.raises(VLMUnreachableError, match="request failed after 3 attempt\\(s\\): ConnectTimeout"):
        client.complete([user_message("x")])
    assert len(timeouts) == 3 and waits == [0.5, 1.0]  # bounded: max_retries + 1 attempts, doubling back-off
    assert all(t["connect"] == 3.0 and t["read"] == 60.0 for t in timeouts)  # type: ignore[index]


@pytest.mark.parametrize("reply", [{"choices": []}, {"choices": [{"message": {"content": "   "}}]}, {"id": "x"}])
def test_answers_without_text_are_errors(server: ChatServer, reply) -> None:
    server.reply = lambda body: (200, reply)
    with pytest.raises(VLMError, match="chat/completions"):
        _client(server).complete([user_message("x")])


def test_config_from_env_and_its_validation(monkeypatch) -> None:
    monkeypatch.delenv(ENV_URL, raising=False)
    monkeypatch.delenv(ENV_MODEL, raising=False)
    with pytest.raises(VLMError, match=f"{ENV_URL} and {ENV_MODEL}"):
        OpenAIChatConfig.from_env()
    monkeypatch.setenv(ENV_URL, "http://127.0.0.1:9/v1")
    monkeypatch.setenv(ENV_MODEL, "llava")
    config = OpenAIChatConfig.from_env(max_retries=0)
    assert config.url == "http://127.0.0.1:9/v1/chat/completions" and config.model == "llava"
    with pytest.raises(ValueError, match="base_url"):
        OpenAIChatConfig(base_url="127.0.0.1:8000", model="m")
    with pytest.raises(ValueError, match="model"):
        OpenAIChatConfig(base_url="http://x/v1", model="")
