"""A sideways shift of the own path, metres (+ = left)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl
from simsplat_core.editing.parse.predicate import PredicateWork

_N = r"(\d+(?:\.\d+)?)"


def parse_lateral_offset(w: PredicateWork) -> None:
    """"shift 1.5 m to the left" -> ``lateral_offset_m=1.5`` (right: negative)."""
    w.take(r"(?:shift|shifts|move|moves|nudge|nudges|slide|slides|offset|drift|drifts|steer|steers)(?: it| over|"
           r" sideways)?"
           r" " + _N + r" m (?:to the |towards the |over to the |to its )?(left|right)",
           lambda m: w.set("lateral_offset_m", float(m.group(1)) * (1 if m.group(2) == "left" else -1)))


LATERAL_OFFSET = BehaviourDecl(
    "lateral_offset",
    fields=("lateral_offset_m",),
    intents=(),
    motion_classes={},
    proposal_forms={},
    prompt_forms={},
    parse_rule=parse_lateral_offset,
)
