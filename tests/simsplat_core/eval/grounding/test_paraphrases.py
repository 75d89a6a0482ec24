"""Paraphrase realisation: every style works, wordings vary, synonyms and plurals are right."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.eval.grounding.paraphrases import (
    GROUP_STYLES,
    MOTION_TERMS,
    SINGLE_STYLES,
    Wording,
    plural,
    realise,
    realise_group,
)
from simsplat_core.scenario import vocabulary as voc

CAR = Wording("vehicle", "SUV", ("SUV",), color="red", motion=voc.TURNING_LEFT, sector=voc.LEFT_OF_EGO,
              context=voc.AT_THE_INTERSECTION)
PED = Wording("pedestrian", upper="blue", lower="gray", motion="crossing_any", context=voc.ON_THE_CROSSWALK)
GENERIC = Wording("vehicle", None, ("sedan", "hatchback"), color="white", motion=voc.PARKED)


@pytest.mark.parametrize("style", SINGLE_STYLES)
def test_every_style_mentions_every_constraint(style: str) -> None:
    rng = np.random.default_rng(0)
    for _ in range(10):
        text = realise(CAR, style, rng).lower()
        assert "red" in text and ("suv" in text or "sport utility vehicle" in text)
        assert "left" in text
        assert any(w in text for w in ("intersection", "junction", "crossroads")), text
        ped = realise(PED, style, rng).lower()
        assert "blue" in ped and ("gray" in ped or "grey" in ped) and "cross" in ped


@pytest.mark.parametrize("style", GROUP_STYLES)
def test_group_styles_use_plurals_or_quantifiers(style: str) -> None:
    rng = np.random.default_rng(1)
    text = realise_group(GENERIC, style, rng).lower()
    assert "white" in text and "park" in text
    assert any(w in text for w in ("all", "every", "each", "cars", "vehicles")), text


def test_wordings_vary() -> None:
    rng = np.random.default_rng(2)
    texts = {realise(CAR, style, rng) for style in SINGLE_STYLES for _ in range(3)}
    assert len(texts) >= 20
    nouns = {w for t in texts for w in ("SUV", "sport utility vehicle") if w in t}
    assert nouns == {"SUV", "sport utility vehicle"}
    peds = " ".join(realise(PED, "definite", rng) for _ in range(40))
    assert sum(w in peds for w in ("pedestrian", "person", "walker", "passer-by", "individual")) >= 3
    assert sum(w in peds for w in ("top", "shirt", "jacket", "sweater", "hoodie")) >= 3


def test_generic_nouns_fit_the_body_styles() -> None:
    rng = np.random.default_rng(3)
    cars = " ".join(realise(GENERIC, "definite", rng) for _ in range(30))
    assert "car" in cars
    bus = Wording("vehicle", None, ("bus", "sedan"), color="yellow")
    buses = " ".join(realise(bus, "definite", rng) for _ in range(30))
    assert "car" not in buses and "vehicle" in buses


def test_plural_and_article() -> None:
    assert plural("bus") == "buses"
    assert plural("person") == "people"
    assert plural("pickup truck") == "pickup trucks"
    assert plural("sport utility vehicle") == "sport utility vehicles"
    rng = np.random.default_rng(4)
    suv = Wording("vehicle", "SUV", ("SUV",))
    texts = [realise(suv, "descriptive", rng) for _ in range(20)]
    assert any("an SUV" in t for t in texts)
    assert not any("a SUV" in t for t in texts)


def test_motion_terms_cover_vocabulary_classes() -> None:
    from simsplat_core.scenario.vocabulary import MOTION_VOCABULARIES

    covered = {c for _, classes in MOTION_TERMS.values() for c in classes}
    for vocab in MOTION_VOCABULARIES.values():
        assert set(vocab.names) <= covered


def test_unknown_style_raises() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="unknown style"):
        realise(CAR, "shouting", rng)
    with pytest.raises(ValueError, match="unknown group style"):
        realise_group(CAR, "shouting", rng)


def test_no_dangling_clauses_and_unambiguous_turns() -> None:
    rng = np.random.default_rng(5)
    bare = Wording("vehicle", "hatchback", ("hatchback",), color="red")
    for style in SINGLE_STYLES:
        for _ in range(5):
            text = realise(bare, style, rng).rstrip(".?")
            assert not text.endswith(("that is", "that's", "which is", "who is", "who's")), text
    turn = Wording("vehicle", "sedan", ("sedan",), motion="turning_any", sector=voc.LEFT_OF_EGO)
    for style in SINGLE_STYLES:
        for _ in range(5):
            text = realise(turn, style, rng)
            for phrase in ("on my left", "to our left", "on the left-hand side", "to the left of the ego car"):
                if phrase in text:
                    assert text.index(phrase) < max(text.find("turn"), text.find("making a")), text


def test_group_wordings_agree_in_number() -> None:
    rng = np.random.default_rng(6)
    stopped = Wording("vehicle", None, ("sedan",), motion=voc.STOPPED)
    texts = [realise_group(stopped, style, rng) for style in GROUP_STYLES for _ in range(6)]
    assert not any(" its " in t or t.endswith(" its") for t in texts)
    assert any("their lane" in t for t in texts)
