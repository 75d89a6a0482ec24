"""Predictors by name."""

from __future__ import annotations

import pytest

from simsplat_core.motion import registry
from simsplat_core.motion.baselines import ConstantVelocityPredictor, LogReplayPredictor
from simsplat_core.motion.predictor import MotionPredictor
from simsplat_core.motion.reactive import ReactivePredictor
from simsplat_core.motion.registry import (
    DEFAULT_PREDICTOR,
    available_predictors,
    default_predictor,
    make_predictor,
    register,
)


def test_the_built_in_predictors_in_table_order() -> None:
    assert available_predictors()[:3] == ("log", "constant-velocity", "reactive")
    for name, kind in (("log", LogReplayPredictor), ("constant-velocity", ConstantVelocityPredictor),
                       ("reactive", ReactivePredictor)):
        predictor = make_predictor(name)
        assert isinstance(predictor, kind) and isinstance(predictor, MotionPredictor) and predictor.name == name


def test_each_call_builds_a_new_predictor() -> None:
    assert make_predictor("reactive") is not make_predictor("reactive")


def test_the_default_is_the_reactive_model() -> None:
    assert DEFAULT_PREDICTOR == "reactive" and isinstance(default_predictor(), ReactivePredictor)


def test_an_unknown_name_is_named_with_the_known_ones() -> None:
    with pytest.raises(KeyError, match=r"unknown predictor 'smart'; known: \['log', 'constant-velocity', 'reactive'"):
        make_predictor("smart")


def test_register_adds_a_predictor(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))  # leave the module's table as it was

    class Learned(LogReplayPredictor):
        name: str = "learned"

    register("learned", Learned)
    assert available_predictors()[-1] == "learned" and isinstance(make_predictor("learned"), Learned)
