"""Shared fixtures of the language tests: the text encoder, annotation-only synthetic logs, one trained aligner."""

from __future__ import annotations

import pytest

from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
from simsplat_core.language.text import TextEncoder, default_text_encoder
from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

TRAIN_SEEDS = (0, 1, 2, 3)
HELD_OUT_SEED = 104


def annotation_log(seed: int) -> SceneLog:
    """A default-length synthetic log without pixels (about a second to generate)."""
    return generate_log(seed, WorldConfig(render_images=False))


@pytest.fixture(scope="session")
def encoder() -> TextEncoder:
    return default_text_encoder()


@pytest.fixture(scope="session")
def train_logs() -> list[SceneLog]:
    return [annotation_log(seed) for seed in TRAIN_SEEDS]


@pytest.fixture(scope="session")
def held_out_log() -> SceneLog:
    return annotation_log(HELD_OUT_SEED)


@pytest.fixture(scope="session")
def aligner(train_logs: list[SceneLog], encoder: TextEncoder) -> MotionAligner:
    return MotionAligner.fit(train_logs, MotionAlignerConfig(epochs=30), encoder)
