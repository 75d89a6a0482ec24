"""Crossing the street (pedestrians)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.scenario import vocabulary as voc

CROSS_STREET = BehaviourDecl(
    "cross_street",
    fields=("cross_street",),
    agent="pedestrian",
    words="crossing the street",
    intents=(Intent("cross", fields={"cross_street": True}, phrases=("cross the street", "walk across the road")),),
    motion_classes={voc.CROSSING_LEFT_TO_RIGHT: "cross", voc.CROSSING_RIGHT_TO_LEFT: "cross", voc.CROSSING: "cross"},
    proposal_forms={
        "ped_cross": (
            "Make {T} cross the street.",
            "Have {T} walk across the road.",
        ),
        "ped_run_across": (
            "Make {T} run across the road.",
            "Have {T} sprint across the street.",
        ),
    },
    prompt_forms={
        "pedestrian_cross": (
            "Make {T} cross the street.",
            "{T} should walk across the road.",
            "Have {T} cross over to the other side of the street.",
        ),
    },
)
