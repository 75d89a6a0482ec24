"""A small client for OpenAI-compatible chat-completion servers (hosted VLMs, vLLM, llama.cpp, Ollama ...).

    client = OpenAIChatClient(OpenAIChatConfig(base_url="http://127.0.0.1:8000/v1", model="qwen2-vl"))
    text = client.complete([user_message("What colour is this car?", images=[rgb])])

Speaks ``POST {base_url}/chat/completions`` with the standard request body (``model``, ``messages``,
``max_tokens``, ``temperature``) and reads ``choices[0].message.content``. Images travel inline as
``image_url`` parts holding ``data:image/png;base64,...`` URIs, which every OpenAI-compatible vision
server accepts.

The API key is read from the environment variable named by ``OpenAIChatConfig.api_key_env`` at request
time (never stored in the config, never logged, never part of an error message); servers that need no
key get no ``Authorization`` header. Transport errors, 429 and 5xx answers are retried with exponential
back-off; any other failure raises :class:`VLMError` naming the URL, the HTTP status and the server's
message.
"""

from __future__ import annotations

import base64
import logging
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import httpx
import numpy as np

from simsplat_core.viz.images import encode_png, to_uint8

logger = logging.getLogger(__name__)

#: Environment variables read by :meth:`OpenAIChatConfig.from_env`.
ENV_URL = "SIMSPLAT_VLM_URL"
ENV_MODEL = "SIMSPLAT_VLM_MODEL"
ENV_API_KEY = "SIMSPLAT_VLM_API_KEY"
#: HTTP statuses worth retrying (rate limit, server-side trouble).
RETRY_STATUSES = frozenset({408, 429, 500, 502, 503, 504})


class VLMError(RuntimeError):
    """A chat-completion request failed; the message names the URL and what went wrong (never the key)."""


@dataclass(frozen=True)
class OpenAIChatConfig:
    """Where and how to ask.

    Attributes:
        base_url: the API root, e.g. ``"http://127.0.0.1:8000/v1"`` (``/chat/completions`` is appended).
        model: the ``model`` field of every request.
        api_key_env: name of the environment variable holding the API key (unset: no key is sent).
        timeout_s: per-request timeout in seconds.
        max_retries: extra attempts after a transport error or a 408/429/5xx answer.
        backoff_s: first back-off delay; doubles per retry.
    """

    base_url: str
    model: str
    api_key_env: str = ENV_API_KEY
    timeout_s: float = 60.0
    max_retries: int = 2
    backoff_s: float = 0.5

    def __post_init__(self) -> None:
        if not self.base_url.startswith(("http://", "https://")):
            raise ValueError(f"OpenAIChatConfig.base_url must start with http:// or https://, got {self.base_url!r}")
        if not self.model:
            raise ValueError("OpenAIChatConfig.model must name a model")
        if self.timeout_s <= 0:
            raise ValueError(f"OpenAIChatConfig.timeout_s must be > 0, got {self.timeout_s}")
        if self.max_retries < 0 or self.backoff_s < 0:
            raise ValueError(f"OpenAIChatConfig.max_retries and backoff_s must be >= 0, got "
                             f"{self.max_retries} and {self.backoff_s}")

    @property
    def url(self) -> str:
        """The chat-completions endpoint."""
        return self.base_url.rstrip("/") + "/chat/completions"

    @classmethod
    def from_env(cls, **overrides: Any) -> OpenAIChatConfig:
        """From ``SIMSPLAT_VLM_URL`` and ``SIMSPLAT_VLM_MODEL`` (the key stays in ``SIMSPLAT_VLM_API_KEY``).

        Raises:
            VLMError: a variable is unset, naming it.
        """
        missing = [name for name in (ENV_URL, ENV_MODEL) if not os.environ.get(name)]
        if missing:
            raise VLMError(f"no VLM endpoint configured: set {' and '.join(missing)} "
                           f"(and {ENV_API_KEY} if the server needs a key)")
        return cls(base_url=os.environ[ENV_URL], model=os.environ[ENV_MODEL], **overrides)


def png_data_uri(rgb: np.ndarray) -> str:
    """``data:image/png;base64,...`` of an ``[H, W, 3]`` image (float in ``[0, 1]`` or uint8)."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an [H, W, 3] image, got shape {rgb.shape}")
    return "data:image/png;base64," + base64.b64encode(encode_png(to_uint8(rgb))).decode("ascii")


def user_message(text: str, images: Sequence[np.ndarray] = ()) -> dict[str, Any]:
    """A ``user`` chat message: the text, then each ``[H, W, 3]`` image as an inline PNG part."""
    if not images:
        return {"role": "user", "content": text}
    parts: list[dict[str, Any]] = [{"type": "text", "text": text}]
    parts += [{"type": "image_url", "image_url": {"url": png_data_uri(img)}} for img in images]
    return {"role": "user", "content": parts}


def _reply_text(body: Any, url: str) -> str:
    """``choices[0].message.content`` as text (content parts of type ``text`` are joined)."""
    try:
        content = body["choices"][0]["message"]["content"]
    except (KeyError, IndexError, TypeError) as exc:
        raise VLMError(f"{url}: the answer has no choices[0].message.content ({str(body)[:200]!r})") from exc
    if isinstance(content, list):
        content = "".join(p.get("text", "") for p in content if isinstance(p, dict))
    if not isinstance(content, str) or not content.strip():
        raise VLMError(f"{url}: the answer's message content is empty")
    return content.strip()


def _server_message(response: httpx.Response) -> str:
    try:
        body = response.json()
        error = body.get("error", body) if isinstance(body, dict) else body
        message = error.get("message", error) if isinstance(error, dict) else error
        return str(message)[:300]
    except ValueError:
        return response.text[:300]


class OpenAIChatClient:
    """Chat completions over HTTP (module docstring).

    Args:
        config: endpoint, model, key variable, timeouts.
        transport: an ``httpx`` transport (tests may pass ``httpx.MockTransport``); default: the network.
    """

    def __init__(self, config: OpenAIChatConfig, transport: httpx.BaseTransport | None = None) -> None:
        self.config = config
        self._http = httpx.Client(timeout=config.timeout_s, transport=transport)

    def __repr__(self) -> str:
        return f"OpenAIChatClient(url={self.config.url!r}, model={self.config.model!r})"

    @property
    def name(self) -> str:
        """``openai-chat:<model>``: identifies the model in content keys and captions' provenance."""
        return f"openai-chat:{self.config.model}"

    def _headers(self) -> dict[str, str]:
        headers = {"Content-Type": "application/json"}
        key = os.environ.get(self.config.api_key_env, "")
        if key:
            headers["Authorization"] = f"Bearer {key}"
        return headers

    def complete(self, messages: Sequence[dict[str, Any]], *, max_tokens: int = 64, temperature: float = 0.0) -> str:
        """The assistant's reply to ``messages`` (``user_message`` builds them).

        Raises:
            VLMError: the server could not be reached, answered with an error status, or sent no text.
        """
        url = self.config.url
        body = {"model": self.config.model, "messages": list(messages), "max_tokens": int(max_tokens),
                "temperature": float(temperature)}
        delay = self.config.backoff_s
        for attempt in range(self.config.max_retries + 1):
            last = attempt == self.config.max_retries
            try:
                response = self._http.post(url, json=body, headers=self._headers())
            except httpx.HTTPError as exc:
                if last:
                    raise VLMError(f"{url}: request failed after {attempt + 1} attempt(s): "
                                   f"{type(exc).__name__}: {exc}") from exc
                logger.warning("%s: %s, retrying in %.1f s", url, type(exc).__name__, delay)
            else:
                if response.status_code == 200:
                    try:
                        payload = response.json()
                    except ValueError as exc:
                        raise VLMError(f"{url}: the answer is not JSON ({response.text[:200]!r})") from exc
                    return _reply_text(payload, url)
                message = _server_message(response)
                if response.status_code not in RETRY_STATUSES or last:
                    raise VLMError(f"{url}: HTTP {response.status_code} after {attempt + 1} attempt(s): {message}")
                logger.warning("%s: HTTP %d (%s), retrying in %.1f s", url, response.status_code, message, delay)
            time.sleep(delay)
            delay *= 2
        raise AssertionError("unreachable")

    def close(self) -> None:
        self._http.close()


__all__ = [
    "ENV_API_KEY",
    "ENV_MODEL",
    "ENV_URL",
    "OpenAIChatClient",
    "OpenAIChatConfig",
    "VLMError",
    "png_data_uri",
    "user_message",
]
