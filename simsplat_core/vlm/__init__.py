"""Talking to vision-language models over the OpenAI-compatible chat-completions protocol."""

from simsplat_core.vlm.openai_chat import (
    ENV_API_KEY,
    ENV_MODEL,
    ENV_URL,
    OpenAIChatClient,
    OpenAIChatConfig,
    VLMError,
    png_data_uri,
    user_message,
)

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
