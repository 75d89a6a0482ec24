"""Shared inputs of the appearance tests: one small synthetic log and its object crops."""

from __future__ import annotations

import pytest

from simsplat_core.language.appearance.crops import ObjectCrop, crops_from_log
from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

#: A 20-frame sequence with vehicles, pedestrians and street furniture all in view.
WORLD_SEED = 25
MIN_AREA = 100


@pytest.fixture(scope="session")
def world_log() -> SceneLog:
    return generate_log(WORLD_SEED, WorldConfig(num_frames=20))


@pytest.fixture(scope="session")
def world_crops(world_log: SceneLog) -> list[ObjectCrop]:
    return crops_from_log(world_log, min_area=MIN_AREA)
