"""Turning left or right, or going straight, at the next intersection (vehicles)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.scenario import vocabulary as voc

TURN = BehaviourDecl(
    "turn",
    fields=("turn",),
    agent="vehicle",
    words="turning at an intersection",
    intents=(
        Intent("turn_left", fields={"turn": "left"}, phrases=("turn left at the intersection", "make a left turn")),
        Intent("turn_right", fields={"turn": "right"}, phrases=("turn right at the intersection", "make a right turn")),
        Intent("straight", fields={"turn": "straight"}, phrases=("go straight through the intersection",)),
    ),
    motion_classes={voc.TURNING_LEFT: "turn_left", voc.TURNING_RIGHT: "turn_right", voc.GOING_STRAIGHT: "straight"},
    proposal_forms={
        "turn": (
            "Make {T} turn {side} at the intersection.",
            "{T} should take a {side}.",
            "Have {T} go {side} at the next junction.",
        ),
    },
    prompt_forms={
        "vehicle_turn": (
            "Make {T} turn {side} at the intersection.",
            "{T} should take a {side} at the next junction.",
            "Have {T} turn {side} at the crossroads.",
            "Let {T} make a {side} turn at the next intersection.",
        ),
        "vehicle_straight": (
            "Make {T} go straight through the intersection.",
            "{T} should continue straight instead of turning.",
            "Have {T} drive straight on at the junction.",
        ),
        "turn_no_intersection": (
            "Make {T} turn {side} at the next intersection.",
            "{T} should take a {side} at the next junction.",
        ),
    },
)
