"""Fixtures of the scene tests: a tiny synthetic log (8 frames, 64x48, frames 3 and 7 held out)."""

from __future__ import annotations

import pytest

from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log


@pytest.fixture(scope="session")
def tiny_log() -> SceneLog:
    return generate_log(3, WorldConfig(num_frames=8, width=64, height=48, test_every=4))
