"""Crossing the street away from any crosswalk (pedestrians)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent

JAYWALK = BehaviourDecl(
    "jaywalk",
    fields=("jaywalk",),
    agent="pedestrian",
    words="jaywalking",
    intents=(Intent("jaywalk", fields={"jaywalk": True, "cross_street": True}),),
    motion_classes={},
    proposal_forms={
        "ped_jaywalk": (
            "Make {T} jaywalk across the road.",
            "Have {T} cross the street away from the crosswalk.",
            "{T} should jaywalk.",
        ),
    },
    prompt_forms={
        "pedestrian_jaywalk": (
            "Make {T} jaywalk across the road.",
            "{T} should cross the street away from the crosswalk.",
            "Have {T} jaywalk across the street.",
        ),
    },
)
