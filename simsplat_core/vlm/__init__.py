"""Talking to vision-language models over the OpenAI-compatible chat-completions protocol."""

from simsplat_core.vlm.openai_chat import (
    ENV_API_KEY,
    ENV_MODEL,
    ENV_URL,
    MAX_RETRY_AFTER_S,
    OpenAIChatClient,
    OpenAIChatConfig,
    VLMError,
    VLMUnreachableError,
    png_data_uri,
    user_message,
)
from simsplat_core.vlm.tool_calls import ToolAnswerError, tool_arguments, tool_request_fields

__all__ = [
    "ENV_API_KEY",
    "ENV_MODEL",
    "ENV_URL",
    "MAX_RETRY_AFTER_S",
    "OpenAIChatClient",
    "OpenAIChatConfig",
    "ToolAnswerError",
    "VLMError",
    "VLMUnreachableError",
    "png_data_uri",
    "tool_arguments",
    "tool_request_fields",
    "user_message",
]
