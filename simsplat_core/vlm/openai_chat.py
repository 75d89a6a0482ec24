"""A small client for OpenAI-compatible chat-completion servers (hosted VLMs, vLLM, llama.cpp, Ollama ...).

    client = OpenAIChatClient(OpenAIChatConfig(base_url="http://127.0.0.1:8000/v1", model="qwen2-vl"))
    text = client.complete([user_message("What colour is this car?", images=[rgb])])

    program = client.call_tool([user_message("Make the red car stop.")], "emit_edit_program", "The edit.",
                               edit_program_json_schema(), EditProgram.model_validate)

Speaks ``POST {base_url}/chat/completions`` with the standard request body (``model``, ``messages``,
``max_tokens``, ``temperature``) and reads ``choices[0].message.content``. Images travel inline as
``image_url`` parts holding ``data:image/png;base64,...`` URIs, which every OpenAI-compatible vision
server accepts.

:meth:`OpenAIChatClient.call_tool` adds function calling: one function whose parameters are a JSON Schema,
forced with ``tool_choice``; the arguments (or, from servers without tool calling, a JSON object in the
content) are parsed and validated by the caller's validator. Malformed JSON, a missing call and arguments
that fail validation are retried with what was wrong appended to the conversation (``max_retries`` times,
with back-off), then raise :class:`VLMError` naming the URL, the tool and the failing field
(``tool_calls`` holds the parsing helpers).

The API key is read from the environment variable named by ``OpenAIChatConfig.api_key_env`` at request
time (never stored in the config, never logged, never part of an error message: a server that echoes it
gets it masked); servers that need no key get no ``Authorization`` header. Transport errors (timeouts
included), 408, 429 and 5xx answers are retried with exponential back-off (at least a 429's
``Retry-After``, capped at :data:`MAX_RETRY_AFTER_S`); any other failure raises :class:`VLMError` naming
the URL, the HTTP status and the server's message. A server that cannot be reached at all fails each call
after ``max_retries + 1`` connection attempts of at most ``connect_timeout_s`` each (plus the back-off: about
1.5 s with the defaults when the port is closed) with :class:`VLMUnreachableError`, so a caller can tell an
endpoint that is down from one that answers badly. At most ``max_concurrency`` requests of one client are
in flight at once, whichever threads send them.
"""

from __future__ import annotations

import base64
import logging
import os
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import httpx
import numpy as np

from simsplat_core.viz.images import encode_png, to_uint8
from simsplat_core.vlm.tool_calls import ToolAnswerError, tool_arguments, tool_request_fields, validated

logger = logging.getLogger(__name__)

#: Environment variables read by :meth:`OpenAIChatConfig.from_env`.
ENV_URL = "SIMSPLAT_VLM_URL"
ENV_MODEL = "SIMSPLAT_VLM_MODEL"
ENV_API_KEY = "SIMSPLAT_VLM_API_KEY"
#: HTTP statuses worth retrying (rate limit, server-side trouble).
RETRY_STATUSES = frozenset({408, 429, 500, 502, 503, 504})
#: Longest wait a server's ``Retry-After`` header can ask for (seconds).
MAX_RETRY_AFTER_S = 60.0
#: Characters of a rejected answer echoed back to the model in a retry turn.
RETRY_ECHO_CHARS = 2000

T = TypeVar("T")


class VLMError(RuntimeError):
    """A chat-completion request failed; the message names the URL and what went wrong (never the key)."""


class VLMUnreachableError(VLMError):
    """No answer at all: every attempt of a request failed in transport (refused, reset, timed out)."""


@dataclass(frozen=True)
class OpenAIChatConfig:
    """Where and how to ask.

    Attributes:
        base_url: the API root, e.g. ``"http://127.0.0.1:8000/v1"`` (``/chat/completions`` is appended).
        model: the ``model`` field of every request.
        api_key_env: name of the environment variable holding the API key (unset: no key is sent).
        timeout_s: per-request timeout in seconds (reading, writing).
        connect_timeout_s: how long to wait for a connection (a host that drops packets fails after this, not
            after ``timeout_s``).
        max_retries: extra attempts after a transport error or a 408/429/5xx answer; ``call_tool`` also makes
            up to this many extra attempts after a malformed or invalid answer.
        backoff_s: first back-off delay; doubles per retry.
        max_concurrency: most requests of one client in flight at once (across threads).
    """

    base_url: str
    model: str
    api_key_env: str = ENV_API_KEY
    timeout_s: float = 60.0
    connect_timeout_s: float = 10.0
    max_retries: int = 2
    backoff_s: float = 0.5
    max_concurrency: int = 4

    def __post_init__(self) -> None:
        if not self.base_url.startswith(("http://", "https://")):
            raise ValueError(f"OpenAIChatConfig.base_url must start with http:// or https://, got {self.base_url!r}")
        if not self.model:
            raise ValueError("OpenAIChatConfig.model must name a model")
        if self.timeout_s <= 0 or self.connect_timeout_s <= 0:
            raise ValueError(f"OpenAIChatConfig.timeout_s and connect_timeout_s must be > 0, got {self.timeout_s} "
                             f"and {self.connect_timeout_s}")
        if self.max_retries < 0 or self.backoff_s < 0:
            raise ValueError(f"OpenAIChatConfig.max_retries and backoff_s must be >= 0, got "
                             f"{self.max_retries} and {self.backoff_s}")
        if self.max_concurrency < 1:
            raise ValueError(f"OpenAIChatConfig.max_concurrency must be >= 1, got {self.max_concurrency}")

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


def _retry_after_s(response: httpx.Response) -> float:
    """A ``Retry-After: <seconds>`` header as seconds (0 when absent or an HTTP date), capped."""
    try:
        return min(max(float(response.headers.get("Retry-After", "0")), 0.0), MAX_RETRY_AFTER_S)
    except ValueError:
        return 0.0


class OpenAIChatClient:
    """Chat completions and function calls over HTTP (module docstring).

    Args:
        config: endpoint, model, key variable, timeouts, retries, concurrency.
        transport: an ``httpx`` transport (tests may pass ``httpx.MockTransport``); default: the network.
        sleep: how to wait between retries (tests may record the back-off instead of waiting).
    """

    def __init__(self, config: OpenAIChatConfig, transport: httpx.BaseTransport | None = None, *,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.config = config
        timeout = httpx.Timeout(config.timeout_s, connect=min(config.connect_timeout_s, config.timeout_s))
        self._http = httpx.Client(timeout=timeout, transport=transport)
        self._slots = threading.BoundedSemaphore(config.max_concurrency)
        self._sleep = sleep

    def __repr__(self) -> str:
        return f"OpenAIChatClient(url={self.config.url!r}, model={self.config.model!r})"

    @property
    def name(self) -> str:
        """``openai-chat:<model>``: identifies the model in content keys and captions' provenance."""
        return f"openai-chat:{self.config.model}"

    def _key(self) -> str:
        return os.environ.get(self.config.api_key_env, "")

    def _headers(self) -> dict[str, str]:
        headers = {"Content-Type": "application/json"}
        key = self._key()
        if key:
            headers["Authorization"] = f"Bearer {key}"
        return headers

    def _redact(self, text: str) -> str:
        """``text`` with the API key (should a server or an exception echo it) masked."""
        key = self._key()
        return text.replace(key, "***") if key else text

    def _post(self, body: dict[str, Any]) -> Any:
        """POST ``body`` to the endpoint and return the decoded JSON answer of a 200.

        Transport errors (timeouts included) and 408/429/5xx are retried ``config.max_retries`` times with
        back-off; each attempt holds one of the client's ``max_concurrency`` slots while it is in flight.

        Raises:
            VLMUnreachableError: every attempt failed in transport (the endpoint is down or unreachable).
            VLMError: retries ran out on error statuses, another status came back, or the answer is not JSON.
        """
        url = self.config.url
        delay = self.config.backoff_s
        for attempt in range(self.config.max_retries + 1):
            last = attempt == self.config.max_retries
            wait = delay
            try:
                with self._slots:
                    response = self._http.post(url, json=body, headers=self._headers())
            except httpx.HTTPError as exc:
                if last:
                    raise VLMUnreachableError(self._redact(f"{url}: request failed after {attempt + 1} attempt(s): "
                                                           f"{type(exc).__name__}: {exc}")) from exc
                logger.warning("%s: %s, retrying in %.2f s", url, type(exc).__name__, wait)
            else:
                if response.status_code == 200:
                    try:
                        return response.json()
                    except ValueError as exc:
                        problem = f"{url}: the answer is not JSON ({response.text[:200]!r})"
                        raise VLMError(self._redact(problem)) from exc
                message = self._redact(_server_message(response))
                if response.status_code not in RETRY_STATUSES or last:
                    raise VLMError(f"{url}: HTTP {response.status_code} after {attempt + 1} attempt(s): {message}")
                if response.status_code == 429:
                    wait = max(wait, _retry_after_s(response))
                logger.warning("%s: HTTP %d (%s), retrying in %.2f s", url, response.status_code, message, wait)
            self._sleep(wait)
            delay *= 2
        raise AssertionError("unreachable")

    def complete(self, messages: Sequence[dict[str, Any]], *, max_tokens: int = 64, temperature: float = 0.0) -> str:
        """The assistant's reply to ``messages`` (``user_message`` builds them).

        Raises:
            VLMError: the server could not be reached, answered with an error status, or sent no text.
        """
        body = {"model": self.config.model, "messages": list(messages), "max_tokens": int(max_tokens),
                "temperature": float(temperature)}
        payload = self._post(body)
        try:
            return _reply_text(payload, self.config.url)
        except VLMError as exc:
            raise VLMError(self._redact(str(exc))) from exc

    def call_tool(self, messages: Sequence[dict[str, Any]], tool_name: str, description: str,
                  parameters_schema: dict[str, Any], validate: Callable[[dict[str, Any]], T], *,
                  max_tokens: int = 1024, temperature: float = 0.0) -> T:
        """Ask for a call of the function ``tool_name`` (arguments per ``parameters_schema``); ``validate`` them.

        Args:
            messages: the conversation (``user_message`` builds them; a ``system`` message may lead).
            tool_name: the function's name (``[A-Za-z0-9_-]``, at most 64 characters).
            description: what the function is for (the model reads it).
            parameters_schema: JSON Schema of the arguments object (e.g. a pydantic ``model_json_schema()``).
            validate: arguments dict -> the result; raises ``pydantic.ValidationError`` / ``ValueError`` when
                they are invalid (e.g. ``EditProgram.model_validate``).
            max_tokens, temperature: sampling settings of every attempt.

        Returns:
            ``validate``'s result for the first valid answer.

        Raises:
            VLMError: an HTTP failure (after its own retries, see :meth:`_post`), or ``config.max_retries + 1``
                answers in a row that were malformed or invalid; the message names the URL, the tool and what
                was wrong with the last answer (the failing field's path for a validation error).
        """
        url = self.config.url
        conversation = list(messages)
        fields = tool_request_fields(tool_name, description, parameters_schema)
        delay = self.config.backoff_s
        for attempt in range(self.config.max_retries + 1):
            body = {"model": self.config.model, "messages": conversation, "max_tokens": int(max_tokens),
                    "temperature": float(temperature), **fields}
            payload = self._post(body)
            try:
                return validated(tool_arguments(payload, tool_name), validate, tool_name)
            except ToolAnswerError as exc:
                problem = self._redact(str(exc))
                if attempt == self.config.max_retries:
                    raise VLMError(f"{url}: tool {tool_name}: no valid answer after {attempt + 1} attempt(s): "
                                   f"{problem}") from exc
                logger.warning("%s: tool %s: invalid answer (%s), retrying in %.2f s", url, tool_name, problem, delay)
                conversation += [
                    {"role": "assistant", "content": self._redact(exc.raw[:RETRY_ECHO_CHARS]) or "(no tool call)"},
                    {"role": "user", "content": f"That answer was invalid: {problem}. Call the function {tool_name} "
                                                f"again with arguments that fix this and follow its JSON Schema."},
                ]
            self._sleep(delay)
            delay *= 2
        raise AssertionError("unreachable")

    def close(self) -> None:
        self._http.close()


__all__ = [
    "ENV_API_KEY",
    "ENV_MODEL",
    "ENV_URL",
    "MAX_RETRY_AFTER_S",
    "OpenAIChatClient",
    "OpenAIChatConfig",
    "VLMError",
    "VLMUnreachableError",
    "png_data_uri",
    "user_message",
]
