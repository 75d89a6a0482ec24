"""Fixtures shared by the VLM client tests (``vlm/``, ``mining/``): a local OpenAI-compatible server on 127.0.0.1."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.simsplat_core.vlm.chat_server import ChatServer


@pytest.fixture(scope="module")
def module_server() -> Iterator[ChatServer]:
    """One local chat server per test module."""
    srv = ChatServer().start()
    yield srv
    srv.stop()


@pytest.fixture()
def server(module_server: ChatServer) -> ChatServer:
    """The module's chat server, its script and request log reset for the test."""
    return module_server.reset()
