"""Shared fixtures of the editing-evaluation tests: two rendered synthetic scenes and their prompt set."""

from __future__ import annotations

import pytest

from simsplat_core.eval.editing.prompts import EditPrompt, PromptConfig, build_prompt_set
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.world import generate_log


@pytest.fixture(scope="session")
def truths() -> list[SceneTruth]:
    """Seeds 0 and 1 at the default config (the demo store's scenes), nodes in log order."""
    return [SceneTruth.from_log(generate_log(seed)) for seed in (0, 1)]


@pytest.fixture(scope="session")
def prompts(truths: list[SceneTruth]) -> list[EditPrompt]:
    return build_prompt_set(truths, PromptConfig(per_category=30, infeasible=20))
