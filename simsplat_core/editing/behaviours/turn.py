"""Turning left or right, or going straight, at the next intersection (vehicles)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent, LabelCheck
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

#: Where a turn is made ("at the crossroads", "through the next crossing"): words that add nothing to it.
_TURN_PLACE = (r"(?:at|in|into|through|across|on|by) (?:the |a )?(?:next |first |upcoming |coming |nearest )?"
               r"(?:" + voc.INTERSECTION_RX + r"|crossing)")
#: "... straight instead of turning (left)": the turn given up is part of the go-straight phrase.
_NOT_TURNING = (r"(?:,? (?:instead of|rather than|and not)(?: (?:making|taking|doing))?(?: (?:a|an|the|its|their))?"
                r"(?: (?:left|right)(?:[- ]hand)?)? turn(?:ing|s)?(?: (?:off )?(?:to the )?(?:left|right)"
                r"(?:[- ]hand)?)?)?")


def parse_turn(w: PredicateWork) -> None:
    """"turn left", "take a right", "go straight (instead of turning)", "do not turn" -> ``turn``; a U-turn is
    refused. Runs before the speed rule: "do not turn" is not a negated speed."""
    if w.take(r"u[- ]?turn|u[- ]?turns|turn(?:s)? (?:it |them )?(?:around|back)|do a 180|pull a 180"):
        w.out.refusal = "U-turns are not supported (turn left or right, or go straight, at the next intersection)"
        w.out.refusal_field = "turn"
    w.take(r"(?:(?:do not|does not|not|never|no|without) turn(?:ing)?(?: (?:left|right))?"
           r"|(?:go|goes|going|drive|drives|driving|continue"
           r"|continues|continuing|keep|keeps|keep going|keep driving|carry on|carries on|head|heads|proceed|proceeds"
           r"|stay|stays|travel|travels|run)(?: on)? straight(?: on| ahead| through| across)?|"
           r"straight (?:through|across"
           r"|on|ahead))" + _NOT_TURNING, lambda m: w.set("turn", "straight"))
    w.take(r"(?:turn|turns|turning|hang|hangs|take|takes|make|makes|swing|swings|bear|bears|go|goes|head|heads|hook"
           r"|hooks)(?: off)?(?: a| an| the)?(?: (?:next|first|upcoming))? (?:to the )?(left|right)(?:[- ]hand)?"
           r"(?: turn)?(?! lane)|(left|right)(?:[- ]hand)? turn",
           lambda m: w.set("turn", m.group(1) or m.group(2)))
    if "turn" in w.out.fields:  # where the turn is made: a "crossing" there is the intersection, not a crosswalk
        w.take(_TURN_PLACE)


def turn_class(side: str) -> str:
    """The motion class of a turn to ``side`` (``"left"`` -> ``"turning_left"``)."""
    return next(c for c, intent in TURN.motion_classes.items() if intent == f"turn_{side}")


def _labelled_turn(turn: str, motion: str) -> bool:
    """A turn to a side shows as that side's turning class; going straight as any class but turning."""
    if turn == "straight":
        return TURN.motion_classes.get(motion) not in ("turn_left", "turn_right")
    return motion == turn_class(turn)


def _turn_missing(turn: str) -> str:
    return "asked to go straight" if turn == "straight" else f"asked {turn_class(turn)}"


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
    parse_rule=parse_turn,
    label_check=LabelCheck("turn", _labelled_turn, _turn_missing),
)
