"""Function calling over the OpenAI-compatible protocol: the request fields, reading the answer, naming what was wrong.

Pure helpers (no HTTP) used by :meth:`simsplat_core.vlm.openai_chat.OpenAIChatClient.call_tool`:

* :func:`tool_request_fields` -- the ``tools`` / ``tool_choice`` fields that force one named function whose
  arguments follow a JSON Schema;
* :func:`tool_arguments` -- the JSON object a model answered with: ``choices[0].message.tool_calls[i].function
  .arguments`` of the named function (a JSON string, or already an object), or, for servers without tool
  calling, a JSON object in ``message.content`` (bare, inside a Markdown code fence, or wrapped as
  ``{"name": ..., "arguments"|"parameters": {...}}``);
* :func:`validated` -- runs the caller's validator and turns a :class:`pydantic.ValidationError` (or a
  ``ValueError``) into a :class:`ToolAnswerError` whose message names each failing field by its path
  (``commands.0.op: Input should be 'insert', ...``).

Every problem with the model's output is a :class:`ToolAnswerError`: the client retries it with the message
appended to the conversation, so the model learns what to fix.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from pydantic import ValidationError

T = TypeVar("T")

#: A Markdown code fence around a JSON answer (```json ... ``` or ``` ... ```).
_FENCE = re.compile(r"^```[A-Za-z0-9_-]*\s*\n?(.*?)\n?```$", re.DOTALL)
#: Characters of the model's output quoted in error messages.
EXCERPT_CHARS = 200


class ToolAnswerError(ValueError):
    """The model's answer was no valid call of the tool; the message says what was wrong (and where).

    Attributes:
        raw: the model's output as text (the arguments string, or the message content), for the retry turn.
    """

    def __init__(self, message: str, raw: str = "") -> None:
        super().__init__(message)
        self.raw = raw


def tool_request_fields(tool_name: str, description: str, parameters_schema: Mapping[str, Any]) -> dict[str, Any]:
    """``{"tools": [...], "tool_choice": {...}}``: one function ``tool_name`` taking ``parameters_schema``, forced."""
    if not re.fullmatch(r"[A-Za-z0-9_-]{1,64}", tool_name):
        raise ValueError(f"tool names are 1..64 of [A-Za-z0-9_-], got {tool_name!r}")
    function = {"name": tool_name, "description": description, "parameters": dict(parameters_schema)}
    return {"tools": [{"type": "function", "function": function}],
            "tool_choice": {"type": "function", "function": {"name": tool_name}}}


def _excerpt(text: str) -> str:
    return repr(text[:EXCERPT_CHARS] + ("..." if len(text) > EXCERPT_CHARS else ""))


def _parse_object(text: str, what: str) -> dict[str, Any]:
    """The JSON object in ``text`` (a Markdown code fence around it is dropped)."""
    stripped = text.strip()
    fenced = _FENCE.match(stripped)
    if fenced:
        stripped = fenced.group(1).strip()
    try:
        value = json.loads(stripped)
    except json.JSONDecodeError as exc:
        raise ToolAnswerError(f"{what} are not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno}): "
                              f"{_excerpt(text)}", raw=text) from exc
    if not isinstance(value, dict):
        raise ToolAnswerError(f"{what} must be a JSON object, got {type(value).__name__}: {_excerpt(text)}", raw=text)
    return value


def _as_object(arguments: Any, what: str) -> dict[str, Any]:
    if isinstance(arguments, str):
        return _parse_object(arguments, what)
    if isinstance(arguments, dict):
        return arguments
    raise ToolAnswerError(f"{what} must be a JSON object or a JSON string, got {type(arguments).__name__}",
                          raw=str(arguments))


def _content_text(content: Any) -> str:
    if isinstance(content, list):
        return "".join(p.get("text", "") for p in content if isinstance(p, dict))
    return content if isinstance(content, str) else ""


def tool_arguments(payload: Any, tool_name: str) -> dict[str, Any]:
    """The arguments object of the model's call of ``tool_name`` in a chat-completion answer (module docstring).

    Raises:
        ToolAnswerError: no message, no call of ``tool_name`` and no JSON object in the content, arguments that
            are not a JSON object; the message says which (and that the answer was cut off at ``max_tokens``
            when ``finish_reason`` is ``"length"``).
    """
    try:
        choice = payload["choices"][0]
        message = choice["message"]
    except (KeyError, IndexError, TypeError) as exc:
        raise ToolAnswerError(f"the answer has no choices[0].message ({str(payload)[:EXCERPT_CHARS]!r})",
                              raw=str(payload)[:EXCERPT_CHARS]) from exc
    if not isinstance(message, dict):
        raise ToolAnswerError("choices[0].message is not an object", raw=str(message)[:EXCERPT_CHARS])
    cut = " (the answer was cut off at max_tokens)" if choice.get("finish_reason") == "length" else ""
    try:
        return _tool_arguments(message, tool_name)
    except ToolAnswerError as exc:
        if not cut:
            raise
        raise ToolAnswerError(f"{exc}{cut}", raw=exc.raw) from exc


def _tool_arguments(message: dict[str, Any], tool_name: str) -> dict[str, Any]:
    calls = message.get("tool_calls") or []
    if isinstance(calls, list) and calls:
        names = []
        for call in calls:
            function = call.get("function") if isinstance(call, dict) else None
            if not isinstance(function, dict):
                continue
            names.append(str(function.get("name")))
            if function.get("name") == tool_name:
                if "arguments" not in function:
                    raise ToolAnswerError(f"the call of {tool_name} has no arguments")
                return _as_object(function["arguments"], f"the arguments of {tool_name}")
        raise ToolAnswerError(f"called {', '.join(names) or 'an unnamed function'} instead of {tool_name}",
                              raw=json.dumps(calls)[:EXCERPT_CHARS])
    text = _content_text(message.get("content"))
    if not text.strip():
        raise ToolAnswerError(f"the answer holds no call of {tool_name} and no content")
    if "{" not in text:
        raise ToolAnswerError(f"the answer holds no call of {tool_name} and no JSON object: {_excerpt(text)}",
                              raw=text)
    value = _parse_object(text, "the message content (no tool call was made)")
    wrapped = value.get("arguments", value.get("parameters"))
    if value.get("name") == tool_name and wrapped is not None:
        return _as_object(wrapped, f"the arguments of {tool_name}")
    return value


def describe_validation_error(error: ValidationError, limit: int = 5) -> str:
    """``path: message (got value)`` for the first ``limit`` errors of ``error``, joined by ``"; "``."""
    parts = []
    for item in error.errors(include_url=False)[:limit]:
        path = ".".join(str(p) for p in item.get("loc", ())) or "(top level)"
        got = item.get("input")
        shown = f" (got {json.dumps(got, default=str)[:60]})" if isinstance(got, (str, int, float, bool)) else ""
        parts.append(f"{path}: {item.get('msg', 'invalid')}{shown}")
    more = error.error_count() - limit
    return "; ".join(parts) + (f"; and {more} more" if more > 0 else "")


def validated(arguments: dict[str, Any], validate: Callable[[dict[str, Any]], T], tool_name: str) -> T:
    """``validate(arguments)``; a failure becomes a :class:`ToolAnswerError` naming the failing fields.

    Raises:
        ToolAnswerError: ``validate`` raised :class:`pydantic.ValidationError`, ``ValueError``, ``KeyError``
            or ``TypeError``.
    """
    try:
        return validate(arguments)
    except ValidationError as exc:
        detail = describe_validation_error(exc)
    except ToolAnswerError:
        raise
    except (ValueError, KeyError, TypeError) as exc:
        detail = f"{type(exc).__name__}: {exc}"
    raw = json.dumps(arguments, default=str)
    raise ToolAnswerError(f"the arguments of {tool_name} do not follow its schema: {detail}", raw=raw)


__all__ = [
    "ToolAnswerError",
    "describe_validation_error",
    "tool_arguments",
    "tool_request_fields",
    "validated",
]
