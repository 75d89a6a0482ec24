"""Driving backwards along the own path (vehicles)."""

import re

from simsplat_core.editing.behaviours.declaration import AgentKind, BehaviourDecl, Intent, LabelCheck
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

#: Where a car reverses out of ("out of its parking space"): words that add nothing to the reversing.
_OUT_OF_SPOT = (r"(?: out)?(?: of (?:its|the|his|her|their|a) (?:parking )?(?:spot|space|bay|place|slot|driveway|"
                r"parking))?")

#: Reversing speed, m/s.
REVERSE_MPS = 2.0


def parse_reverse(w: PredicateWork) -> None:
    """"reverse", "back up", "drive backwards", "in reverse gear" (out of its spot) -> ``reverse=True``."""
    def reverse(m: re.Match[str]) -> None:
        w.set("reverse", True)

    w.take(r"(?:reverse|reverses|reversing|back(?:s|ing)? (?:up|out|it up)|back up|(?:drive|drives|go|goes|move|moves"
           r"|roll|rolls|head|heads|travel|travels)(?: it)? backwards?|(?:in|into) reverse(?: gear)?)" + _OUT_OF_SPOT,
           reverse)


def _labelled_reversing(asked: bool, motion: str) -> bool:
    """Whether the motion class ``motion`` means reversing."""
    return REVERSE.motion_classes.get(motion) == "reverse"


def reversing_speed(behaviour: Behaviour, current: float, kind: AgentKind) -> float | None:
    """Reversing: :data:`REVERSE_MPS` (backwards: the planner gives it the sign)."""
    return REVERSE_MPS if behaviour.reverse else None


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
    parse_rule=parse_reverse,
    label_check=LabelCheck("reverse", _labelled_reversing, lambda asked: f"not {voc.REVERSING}"),
    speed_rule=reversing_speed,
)
