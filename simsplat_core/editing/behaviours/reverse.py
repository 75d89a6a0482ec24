"""Driving backwards along the own path (vehicles)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.scenario import vocabulary as voc

REVERSE = BehaviourDecl(
    "reverse",
    fields=("reverse",),
    agent="vehicle",
    words="driving in reverse",
    intents=(Intent("reverse", fields={"reverse": True}, phrases=("reverse", "back up", "drive backwards")),),
    motion_classes={voc.REVERSING: "reverse"},
    proposal_forms={
        "reverse": (
            "Make {T} reverse.",
            "{T} should back up.",
            "Put {T} in reverse.",
            "Have {T} drive backwards.",
        ),
    },
    prompt_forms={
        "vehicle_reverse": (
            "Make {T} back up.",
            "{T} should reverse.",
            "Have {T} drive backwards a few meters.",
            "Let {T} reverse out of its spot.",
        ),
    },
)
