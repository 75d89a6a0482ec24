"""Shared fixture of the grounding evaluation tests: the default text encoder."""

from __future__ import annotations

import pytest

from simsplat_core.language.text import TextEncoder, default_text_encoder


@pytest.fixture(scope="session")
def encoder() -> TextEncoder:
    return default_text_encoder()
