"""Shared logs for the world-generator tests: generated once per session (a few seconds each)."""

from __future__ import annotations

import pytest

from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

#: Seeds of the full-size logs: one where the ego turns left, one where it drives straight.
FULL_SEEDS = (2, 7)


@pytest.fixture(scope="session")
def full_logs() -> dict[int, SceneLog]:
    """Default-config (40 frames, 3 cameras, 240x160) logs keyed by seed."""
    return {seed: generate_log(seed, WorldConfig()) for seed in FULL_SEEDS}


@pytest.fixture(scope="session")
def small_config() -> WorldConfig:
    return WorldConfig(num_frames=12, width=96, height=64)
