"""Changing into the neighbour lane on a side (vehicles; the benchmark also asks it of pedestrians, to be refused)."""

import re

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent, LabelCheck
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

_AMBIGUOUS_LANE = r"\b(?:change|changes|changing|switch|switches|swap|swaps)(?: the)? lanes?\b|\blane[- ]change\b"


def parse_lane_change(w: PredicateWork) -> None:
    """"change lanes to the left", "cut in to the right", "into the left lane" -> ``lane_change``; "overtake
    <noun phrase>" -> a lane change to the left and accelerating; a lane change without a side is refused."""
    def lane(m: re.Match[str]) -> None:
        w.set("lane_change", m.group(1))

    verbs = (r"(?:change|changes|changing|switch|switches|shift|shifts|move|moves|merge|merges|cut|cuts|swerve|swerves"
             r"|veer|veers|pull|pulls|hop|hops|slide|slides|drift|drifts|steer|steers|squeeze|squeezes|nudge|nudges)")
    w.take(verbs + r"(?: over| across| in| back)?(?: (?:a |one )?lanes?)?(?: (?:to|into|in to|onto|towards|"
                   r"toward|over to"
           r"|across to|in)(?: the)?)? (left|right)(?:[- ]hand)?(?: side)?(?: lane)?", lane)
    w.take(r"(?:(?:turn|turns|go|goes|get|gets|head|heads|drive|drives|pull|pulls|come|comes)(?: over)? )?"
           r"(?:into|to|in to|onto|over to) the (left|right)(?:[- ]hand)? lane|lane[- ]change (?:to the )?(left|right)"
           r"|(left|right) lane[- ]change", lambda m: w.set("lane_change", next(g for g in m.groups() if g)))
    if w.take(r"(?:overtake|overtakes|overtaking|pass|passes|passing|get past|gets past|go around|goes around)"):
        w.set("lane_change", "left")
        w.set("longitudinal", "accelerate")
        start = w.text.rfind("|") + 1
        phrase, end = w.noun_phrase_after(start)
        if phrase:
            w.blank(start, end)
    if "lane_change" not in w.out.fields and re.search(_AMBIGUOUS_LANE, w.text):
        w.out.refusal = "a lane change needs a side: say 'change lanes to the left' or 'to the right'"
        w.out.refusal_field = "lane_change"
        w.take(_AMBIGUOUS_LANE)


def lane_change_class(side: str) -> str:
    """The motion class of a lane change to ``side`` (``"left"`` -> ``"changing_lane_left"``)."""
    return next(c for c, intent in LANE_CHANGE.motion_classes.items() if intent == f"lane_{side}")


LANE_CHANGE = BehaviourDecl(
    "lane_change",
    fields=("lane_change",),
    agent="vehicle",
    words="changing lanes",
    intents=(
        Intent(
            "lane_left",
            fields={"lane_change": "left"},
            phrases=("change lanes to the left", "merge into the left lane"),
        ),
        Intent(
            "lane_right",
            fields={"lane_change": "right"},
            phrases=("change lanes to the right", "merge into the right lane"),
        ),
    ),
    motion_classes={voc.CHANGING_LANE_LEFT: "lane_left", voc.CHANGING_LANE_RIGHT: "lane_right"},
    proposal_forms={
        "lane_change": (
            "Make {T} change lanes to the {side}.",
            "Have {T} cut in to the {side}.",
            "{T} should merge {side} aggressively.",
            "Make {T} switch to the {side} lane.",
        ),
    },
    prompt_forms={
        "vehicle_lane_change": (
            "Make {T} change lanes to the {side}.",
            "{T} should move into the {side} lane.",
            "Have {T} switch to the lane on its {side}.",
            "Let {T} merge {side}.",
        ),
        "pedestrian_lane_change": (
            "Make {T} change lanes to the {side}.",
            "{T} should switch to the {side} lane.",
        ),
    },
    parse_rule=parse_lane_change,
    label_check=LabelCheck("lane_change", lambda side, motion: motion == lane_change_class(side),
                           lambda side: f"asked {lane_change_class(side)}"),
)
