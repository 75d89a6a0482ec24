"""Crossing the street away from any crosswalk (pedestrians)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.editing.parse.predicate import PredicateWork

#: Crossing away from a crosswalk, in words ("mid-block", "not at the zebra crossing", "illegally").
_AWAY_FROM_CROSSWALK = (r"away from (?:the |any )?(?:crosswalk|zebra(?: crossing)?)|mid[- ]?block|not (?:at|on|using|"
                        r"via) (?:the |a )?"
                        r"(?:crosswalk|zebra(?: crossing)?)|in the middle of the (?:road|street|block)|outside (?:of )?"
                        r"(?:the |a )?"
                        r"(?:crosswalk|zebra(?: crossing)?)|illegally|without (?:using )?(?:the |a )?(?:crosswalk|"
                        r"zebra(?: crossing)?)"
                        r"|where there is no (?:crosswalk|zebra)")


def take_jaywalking(w: PredicateWork) -> bool:
    """Take the words of jaywalking ("jaywalk across the road", "mid-block", ...); whether there were any. The
    street-crossing rule (``cross_street.parse_cross_street``) calls it: a jaywalk is a crossing."""
    return w.take(r"jaywalk\w*(?: (?:across|over))?(?: (?:the|a) (?:street|road))?") | w.take(_AWAY_FROM_CROSSWALK)


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
