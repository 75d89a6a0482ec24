"""A local OpenAI-compatible chat-completions server on 127.0.0.1 for client tests.

``ChatServer`` answers ``POST /v1/chat/completions``; a test scripts its answers with ``reply`` (a
function of the request body returning ``(status, json_body)``) and reads back every request it got
(headers and body) from ``requests``.
"""

from __future__ import annotations

import base64
import json
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import cv2
import numpy as np

Reply = Callable[[dict[str, Any]], tuple[int, Any]]


def text_reply(text: str) -> Reply:
    """Always answer 200 with ``text`` as the assistant message."""
    return lambda body: (200, {"choices": [{"index": 0, "message": {"role": "assistant", "content": text}}]})


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
                out.append(cv2.cvtColor(cv2.imdecode(png, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB))
    return out


@dataclass
class ChatServer:
    """The server (``start`` / ``stop``); ``base_url`` is ``http://127.0.0.1:<port>/v1``."""

    reply: Reply = field(default_factory=lambda: text_reply("a red car"))
    requests: list[dict[str, Any]] = field(default_factory=list)

    def start(self) -> ChatServer:
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:  # noqa: N802 (http.server's name)
                length = int(self.headers.get("Content-Length", 0))
                body = json.loads(self.rfile.read(length) or b"{}")
                server.requests.append({"path": self.path, "headers": dict(self.headers), "body": body})
                if self.path != "/v1/chat/completions":
                    status, payload = 404, {"error": {"message": f"no route {self.path}"}}
                else:
                    status, payload = server.reply(body)
                data = json.dumps(payload).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, *args: Any) -> None:
                pass

        self._httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self._thread = threading.Thread(target=self._httpd.serve_forever, daemon=True)
        self._thread.start()
        return self

    @property
    def base_url(self) -> str:
        return f"http://127.0.0.1:{self._httpd.server_address[1]}/v1"

    def stop(self) -> None:
        self._httpd.shutdown()
        self._httpd.server_close()
