"""A said speed: absolute, a factor or a change (``SpeedSpec``)."""

from simsplat_core.editing.behaviours.declaration import AgentKind, BehaviourDecl
from simsplat_core.editing.behaviours.gait import reference_pace
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.parse.speed import speed_rules


def said_speed(behaviour: Behaviour, current: float, kind: AgentKind) -> float | None:
    """The said speed, a factor or change taken against the agent's pace (``gait.reference_pace``)."""
    return behaviour.speed.target_mps(reference_pace(current, kind)) if behaviour.speed is not None else None


SPEED = BehaviourDecl(
    "speed",
    fields=("speed",),
    intents=(),
    motion_classes={},
    proposal_forms={
        "speed_up": (
            "Make {T} go {v}.",
            "Make {T} drive twice as fast.",
            "{T} should go 50% faster.",
        ),
        "slow_down": (
            "Make {T} slow down.",
            "Have {T} drive at half the speed.",
            "Make {T} go 10 km/h slower.",
        ),
    },
    prompt_forms={
        "vehicle_speed_abs": (
            "Make {T} drive at {v}.",
            "Set the speed of {T} to {v}.",
            "{T} should go {v}.",
            "Have {T} travel at {v}.",
        ),
        "vehicle_speed_rel": (
            "Make {T} {rel}.",
            "{T} should drive {rel}.",
            "Have {T} go {rel}.",
        ),
        "pedestrian_speed_abs": (
            "Make {T} walk at {v}.",
            "{T} should walk at {v}.",
            "Set the walking speed of {T} to {v}.",
        ),
        "pedestrian_speed_rel": (
            "Make {T} walk {rel}.",
            "{T} should move {rel}.",
            "Have {T} walk {rel}.",
        ),
    },
    parse_rule=speed_rules,
    speed_rule=said_speed,
)
