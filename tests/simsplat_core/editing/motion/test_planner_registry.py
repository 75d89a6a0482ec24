"""Every behaviour of the edit language reaches the motion request: by its speed rule, a resolver of its fields, its
fields copied as they are, or a route change; and the speed rules apply in the declared precedence."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.editing.behaviours.declaration import BehaviourDecl
from simsplat_core.editing.behaviours.gait import RUN_MPS, WALK_MPS
from simsplat_core.editing.behaviours.longitudinal import ACCELERATE_DELTA_MPS, DECELERATE_FACTOR
from simsplat_core.editing.behaviours.registry import BEHAVIOURS, INTENT_FIELDS
from simsplat_core.editing.behaviours.reverse import REVERSE_MPS
from simsplat_core.editing.commands import Behaviour, SpeedSpec
from simsplat_core.editing.motion.controller import VEHICLE_ROUTES
from simsplat_core.editing.motion.requests import (
    RESOLVERS,
    PedestrianMotionRequest,
    StartState,
    VehicleMotionRequest,
    copied_fields,
    target_speed,
)

NAMES = {b.name for b in BEHAVIOURS}
COPIED = {"vehicle": copied_fields("vehicle", VehicleMotionRequest),
          "pedestrian": copied_fields("pedestrian", PedestrianMotionRequest)}


def _planned(decl: BehaviourDecl) -> list[str]:
    """How ``decl`` reaches the motion request."""
    ways = ["speed rule"] if decl.speed_rule is not None else []
    ways += [f"resolver {name}" for name, _ in RESOLVERS if name == decl.name]
    ways += [f"field {f}" for fields in COPIED.values() for f in fields if f in decl.fields]
    return ways + [f"route {name}" for name, _ in VEHICLE_ROUTES if name == decl.name]


@pytest.mark.parametrize("decl", BEHAVIOURS, ids=lambda d: d.name)
def test_every_behaviour_has_a_planner(decl: BehaviourDecl) -> None:
    assert _planned(decl), f"behaviour {decl.name!r} reaches no motion request (docs/extending_behaviours.md, step 4)"


def test_the_planner_tables_name_declared_behaviours_once() -> None:
    for table in (RESOLVERS, VEHICLE_ROUTES):
        names = [name for name, _ in table]
        assert len(set(names)) == len(names) and set(names) <= NAMES


def _request(behaviour: Behaviour, kind: str, speed: float = 5.0) -> VehicleMotionRequest | PedestrianMotionRequest:
    cls = VehicleMotionRequest if kind == "vehicle" else PedestrianMotionRequest
    return cls.from_behaviour(behaviour, times=np.arange(10) * 0.1, frame_idx=np.arange(10),
                              start=StartState(0, np.zeros(2), 0.0, speed), size=(1.0, 1.0, 1.0))


@pytest.mark.parametrize("kind", ["vehicle", "pedestrian"])
def test_copied_fields_reach_the_request_as_asked(kind: str) -> None:
    assert COPIED[kind], kind
    for field in COPIED[kind]:
        value = next(fields[field] for fields in INTENT_FIELDS.values() if field in fields)
        assert getattr(_request(Behaviour.model_validate({field: value}), kind), field) == value


def test_a_said_speed_comes_before_a_gait_before_a_speed_change() -> None:
    fast = SpeedSpec(mode="factor", value=2.0)
    assert target_speed(Behaviour(speed=fast, gait="walk"), 1.0, "pedestrian") == pytest.approx(2.0)
    assert target_speed(Behaviour(gait="run", longitudinal="decelerate"), 1.0, "pedestrian") == RUN_MPS
    assert target_speed(Behaviour(longitudinal="decelerate", cross_street=True), 0.0, "pedestrian") == pytest.approx(
        WALK_MPS * DECELERATE_FACTOR)  # a standing person's pace is a walk
    assert target_speed(Behaviour(cross_street=True), 0.0, "pedestrian") == WALK_MPS
    assert target_speed(Behaviour(cross_street=True), 1.2, "pedestrian") is None  # a walker keeps its pace
    speeding_up = target_speed(Behaviour(longitudinal="accelerate"), -4.0, "vehicle")
    assert speeding_up == pytest.approx(4.0 + ACCELERATE_DELTA_MPS)
    assert target_speed(Behaviour(reverse=True), 6.0, "vehicle") == REVERSE_MPS
    assert target_speed(Behaviour(reverse=True, speed=SpeedSpec(value=1.0)), 6.0, "vehicle") == 1.0
    assert target_speed(Behaviour(longitudinal="brake_hard"), 6.0, "vehicle") is None  # a stop, no speed


def test_only_the_rules_of_behaviours_the_agent_may_do_are_asked() -> None:
    assert target_speed(Behaviour(gait="run"), 3.0, "vehicle") is None
    assert target_speed(Behaviour(cross_street=True), 0.0, "vehicle") is None
    assert target_speed(Behaviour(reverse=True), 1.0, "pedestrian") is None
