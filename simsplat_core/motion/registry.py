"""Predictors by name: ``"log"``, ``"constant-velocity"`` and ``"reactive"`` (``motion.reactive``, when present).

    predictor = make_predictor("constant-velocity")
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable

from simsplat_core.motion.baselines import ConstantVelocityPredictor, LogReplayPredictor
from simsplat_core.motion.predictor import MotionPredictor

#: Names :func:`make_predictor` knows, in table order.
PREDICTOR_NAMES: tuple[str, ...] = ("log", "constant-velocity", "reactive")
_BUILTIN: dict[str, Callable[[], MotionPredictor]] = {
    "log": LogReplayPredictor,
    "constant-velocity": ConstantVelocityPredictor,
}


def _reactive() -> MotionPredictor | None:
    try:
        module = importlib.import_module("simsplat_core.motion.reactive")
    except ModuleNotFoundError as exc:
        if exc.name != "simsplat_core.motion.reactive":
            raise  # the module exists but one of its imports is missing: a real error
        return None
    return module.ReactivePredictor()


def available_predictors() -> tuple[str, ...]:
    """The names that can be built here (``"reactive"`` only where ``motion.reactive`` is installed)."""
    has_reactive = importlib.util.find_spec("simsplat_core.motion.reactive") is not None
    return tuple(n for n in PREDICTOR_NAMES if n in _BUILTIN or (n == "reactive" and has_reactive))


def make_predictor(name: str) -> MotionPredictor:
    """The predictor called ``name``.

    Raises:
        KeyError: an unknown name, or ``"reactive"`` where ``simsplat_core.motion.reactive`` is missing (the
            message says so and lists what is available).
    """
    if name in _BUILTIN:
        return _BUILTIN[name]()
    if name == "reactive":
        predictor = _reactive()
        if predictor is None:
            raise KeyError(f"predictor 'reactive' is not available: simsplat_core.motion.reactive is not "
                           f"installed; available: {list(available_predictors())}")
        return predictor
    raise KeyError(f"unknown predictor {name!r}; known: {list(PREDICTOR_NAMES)}")


__all__ = ["PREDICTOR_NAMES", "available_predictors", "make_predictor"]
