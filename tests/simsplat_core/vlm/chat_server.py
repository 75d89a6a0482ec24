"""A local OpenAI-compatible chat-completions server on 127.0.0.1 for client tests.

``ChatServer`` answers ``POST /v1/chat/completions``; a test scripts its answers with ``reply`` (a
function of the request body returning ``(status, json_body)`` or ``(status, json_body, headers)``) and
reads back every request it got (headers and body) from ``requests``, and the most requests it had in
flight at once from ``max_in_flight``.

Reply builders: ``text_reply`` (a text answer), ``tool_reply`` (a function call, arguments as an object or
as a raw -- possibly malformed -- string), ``status_reply`` (an error status), ``slow`` (answer after a
delay), ``sequence`` (one reply per request, the last one repeated).
"""

from __future__ import annotations

import base64
import json
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import cv2
import numpy as np

from simsplat_core.vlm import OpenAIChatClient, OpenAIChatConfig

Reply = Callable[[dict[str, Any]], tuple[Any, ...]]


def text_reply(text: str) -> Reply:
    """Always answer 200 with ``text`` as the assistant message."""
    return lambda body: (200, {"choices": [{"index": 0, "message": {"role": "assistant", "content": text}}]})


def tool_reply(name: str, arguments: dict[str, Any] | str, finish_reason: str = "tool_calls") -> Reply:
    """Always answer 200 with a call of function ``name``; ``arguments`` is JSON-encoded unless it is a string."""
    raw = arguments if isinstance(arguments, str) else json.dumps(arguments)
    message = {"role": "assistant", "content": None,
               "tool_calls": [{"id": "call_0", "type": "function", "function": {"name": name, "arguments": raw}}]}
    return lambda body: (200, {"choices": [{"index": 0, "message": message, "finish_reason": finish_reason}]})


def status_reply(status: int, message: str, headers: dict[str, str] | None = None) -> Reply:
    """Always answer ``status`` with an OpenAI-style error body (and ``headers``)."""
    return lambda body: (status, {"error": {"message": message}}, dict(headers or {}))


def slow(delay_s: float, reply: Reply) -> Reply:
    """``reply`` after ``delay_s`` seconds."""

    def answer(body: dict[str, Any]) -> tuple[Any, ...]:
        time.sleep(delay_s)
        return reply(body)

    return answer


def sequence(*replies: Reply) -> Reply:
    """The i-th request gets ``replies[i]``; requests after the last get the last."""
    lock = threading.Lock()
    state = {"next": 0}

    def answer(body: dict[str, Any]) -> tuple[Any, ...]:
        with lock:
            i = min(state["next"], len(replies) - 1)
            state["next"] += 1
        return replies[i](body)

    return answer


def images_of(body: dict[str, Any]) -> list[np.ndarray]:
    """The ``[H, W, 3]`` uint8 RGB images of a request's inline ``image_url`` PNG parts."""
    out = []
    for message in body["messages"]:
        content = message["content"]
        for part in content if isinstance(content, list) else []:
            if part.get("type") == "image_url":
                url = part["image_url"]["url"]
                assert url.startswith("data:image/png;base64,"), url[:40]
                png = np.frombuffer(base64.b64decode(url.split(",", 1)[1]), np.uint8)
                bgr = cv2.imdecode(png, cv2.IMREAD_COLOR)
                assert bgr is not None, "an image part that is no PNG"
                out.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
    return out


def texts_of(body: dict[str, Any], role: str | None = None) -> list[str]:
    """The text of every message (of ``role`` when given), text parts joined."""
    out = []
    for message in body["messages"]:
        if role is not None and message["role"] != role:
            continue
        content = message["content"]
        if isinstance(content, list):
            content = "".join(p.get("text", "") for p in content if p.get("type") == "text")
        out.append(content or "")
    return out


@dataclass
class ChatServer:
    """The server (``start`` / ``stop``); ``base_url`` is ``http://127.0.0.1:<port>/v1``."""

    reply: Reply = field(default_factory=lambda: text_reply("a red car"))
    requests: list[dict[str, Any]] = field(default_factory=list)
    in_flight: int = 0
    max_in_flight: int = 0

    def __post_init__(self) -> None:
        self._lock = threading.Lock()

    def reset(self, reply: Reply | None = None) -> ChatServer:
        """Forget the requests and the in-flight peak; answer with ``reply`` (default: ``text_reply``)."""
        with self._lock:
            self.reply = reply or text_reply("a red car")
            self.requests = []
            self.max_in_flight = self.in_flight  # a slow answer of an earlier test may still be running
        return self

    def wait_for_in_flight(self, count: int, timeout_s: float = 2.0) -> bool:
        """Block until ``max_in_flight >= count`` (True) or ``timeout_s`` passed (False)."""
        deadline = time.monotonic() + timeout_s
        while self.max_in_flight < count:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.002)
        return True

    def _enter(self) -> None:
        with self._lock:
            self.in_flight += 1
            self.max_in_flight = max(self.max_in_flight, self.in_flight)

    def _leave(self) -> None:
        with self._lock:
            self.in_flight -= 1

    def start(self) -> ChatServer:
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:  # noqa: N802 (http.server's name)
                length = int(self.headers.get("Content-Length", 0))
                body = json.loads(self.rfile.read(length) or b"{}")
                server.requests.append({"path": self.path, "headers": dict(self.headers), "body": body})
                server._enter()
                try:
                    if self.path != "/v1/chat/completions":
                        answer: tuple[Any, ...] = (404, {"error": {"message": f"no route {self.path}"}})
                    else:
                        answer = server.reply(body)
                finally:
                    server._leave()
                status, payload = answer[0], answer[1]
                headers = answer[2] if len(answer) > 2 else {}
                data = payload.encode() if isinstance(payload, str) else json.dumps(payload).encode()
                try:
                    self.send_response(status)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(data)))
                    for name, value in headers.items():
                        self.send_header(name, value)
                    self.end_headers()
                    self.wfile.write(data)
                except (BrokenPipeError, ConnectionResetError):
                    pass  # the client gave up (a timeout test)

            def log_message(self, *args: Any) -> None:
                pass

        self._httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self._thread = threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.05},
                                        daemon=True)
        self._thread.start()
        return self

    @property
    def base_url(self) -> str:
        return f"http://127.0.0.1:{self._httpd.server_address[1]}/v1"

    def stop(self) -> None:
        self._httpd.shutdown()
        self._httpd.server_close()



def chat_client(server: ChatServer, sleeps: list[float] | None = None, **kw: Any) -> OpenAIChatClient:
    """A client of ``server`` with no back-off wait (``sleeps`` records the back-off it would have slept)."""
    kw.setdefault("backoff_s", 0.0)
    config = OpenAIChatConfig(base_url=server.base_url, model="test-vlm", **kw)
    return OpenAIChatClient(config, sleep=sleeps.append if sleeps is not None else lambda s: None)
