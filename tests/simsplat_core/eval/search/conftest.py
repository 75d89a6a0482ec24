"""A small image-less synthetic log shared by the search-evaluation tests."""

from __future__ import annotations

import pytest

from simsplat_core.types import SceneLog
from simsplat_core.world.config import WorldConfig
from simsplat_core.world.generate import generate_log


@pytest.fixture(scope="session")
def synthetic_log() -> SceneLog:
    """30 frames of seed 61 without pixels (pedestrians crossing, cars turning, an ego turning left)."""
    return generate_log(seed=61, config=WorldConfig(num_frames=30, render_images=False))
