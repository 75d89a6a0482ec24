"""Predictors by name: ``"log"``, ``"constant-velocity"`` (``motion.baselines``) and ``"reactive"``
(``motion.reactive``, the default of refinement). These three are all that is registered; :func:`register` adds
another ``MotionPredictor`` factory under a new name (the tests register doubles this way).

    predictor = make_predictor("constant-velocity")
"""

from __future__ import annotations

from collections.abc import Callable

from simsplat_core.motion.baselines import ConstantVelocityPredictor, LogReplayPredictor
from simsplat_core.motion.predictor import MotionPredictor
from simsplat_core.motion.reactive import ReactivePredictor

#: Name of the default predictor of refinement.
DEFAULT_PREDICTOR = "reactive"
_FACTORIES: dict[str, Callable[[], MotionPredictor]] = {
    "log": LogReplayPredictor,
    "constant-velocity": ConstantVelocityPredictor,
    "reactive": ReactivePredictor,
}


def register(name: str, factory: Callable[[], MotionPredictor]) -> None:
    """Make :func:`make_predictor` build ``factory()`` for ``name`` (any ``MotionPredictor``; replaces an existing
    name)."""
    _FACTORIES[name] = factory


def available_predictors() -> tuple[str, ...]:
    """The names :func:`make_predictor` knows, in table order."""
    return tuple(_FACTORIES)


def make_predictor(name: str) -> MotionPredictor:
    """The predictor called ``name``. Raises ``KeyError`` naming the known ones."""
    if name not in _FACTORIES:
        raise KeyError(f"unknown predictor {name!r}; known: {list(_FACTORIES)}")
    return _FACTORIES[name]()


def default_predictor() -> MotionPredictor:
    """The predictor refinement uses unless told otherwise: the reactive traffic model."""
    return make_predictor(DEFAULT_PREDICTOR)


__all__ = ["DEFAULT_PREDICTOR", "available_predictors", "default_predictor", "make_predictor", "register"]
