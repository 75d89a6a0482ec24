"""Threshold calibration of the QueryEngine on the look-alike scene: matches kept, near misses refused."""

from __future__ import annotations

import dataclasses

import pytest

from simsplat_core.eval.grounding.calibration import calibrate_thresholds
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import TextEncoder
from tests.simsplat_core.language.grounding.look_alikes import SPECS, ids
from tests.simsplat_core.language.language_scene_factory import hand_built_scene


@pytest.fixture(scope="module")
def codebooks(encoder: TextEncoder) -> MotionCodebooks:
    return MotionCodebooks.build(encoder)


@pytest.fixture(scope="module")
def scene(encoder: TextEncoder, codebooks: MotionCodebooks) -> LanguageScene:
    return hand_built_scene(SPECS, encoder, codebooks)


@pytest.fixture(scope="module")
def engine(encoder: TextEncoder, codebooks: MotionCodebooks) -> QueryEngine:
    return QueryEngine(encoder, QueryConfig(), codebooks=codebooks)


def test_calibrate_thresholds_separates_matches_from_near_misses(engine: QueryEngine, scene: LanguageScene) -> None:
    examples = [
        (scene, "the red sedan turning left at the intersection", frozenset(ids("A"))),
        (scene, "the blue sedan turning left", frozenset(ids("D"))),
        (scene, "the person in a red shirt and blue pants walking along the sidewalk", frozenset(ids("P4"))),
        (scene, "the white van that is stopped", frozenset(ids("G"))),
        (scene, "the blue sedan going straight", frozenset()),
        (scene, "the red sedan reversing", frozenset()),
        (scene, "the pedestrian crossing from right to left", frozenset()),
        (scene, "all parked SUVs", frozenset(ids("E", "F"))),
        (scene, "all pedestrians walking along the sidewalk", frozenset(ids("P3", "P4"))),
        (scene, "all reversing sedans", frozenset()),
    ]
    loose = engine.with_config(QueryConfig(no_match_threshold=0.0, group_threshold=0.0))
    assert loose.ground(scene, "the red sedan reversing").matches  # without a threshold something is returned
    config = calibrate_thresholds(loose, examples)
    assert 0.0 < config.no_match_threshold < 1.0 and 0.0 < config.group_threshold < 1.0
    calibrated = engine.with_config(config)
    for sc, text, expected in examples:
        assert set(calibrated.ground(sc, text).node_ids) == set(expected), text
    assert dataclasses.replace(config, no_match_threshold=0.0, group_threshold=0.0) == loose.config


def test_calibrate_thresholds_needs_examples(engine: QueryEngine) -> None:
    with pytest.raises(ValueError, match="at least one"):
        calibrate_thresholds(engine, [])
