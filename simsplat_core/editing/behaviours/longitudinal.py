"""Braking hard, slowing down or speeding up without a said speed (``Behaviour.longitudinal``)."""

from simsplat_core.editing.behaviours.declaration import AgentKind, BehaviourDecl, Intent
from simsplat_core.editing.behaviours.gait import RUN_MPS, WALK_MPS, reference_pace
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

#: ``accelerate`` without a speed: a vehicle goes this much faster, m/s; ``decelerate``: an agent slows to this
#: fraction of its pace.
ACCELERATE_DELTA_MPS = 5.0
DECELERATE_FACTOR = 0.5


def parse_longitudinal(w: PredicateWork) -> None:
    """"slow down", "ease off" -> decelerate; "speed up", "floor it", "pull away" -> accelerate (the first one
    read wins); a pedestrian told to "hurry" runs."""
    if w.kind == "pedestrian":
        w.take(r"hurry(?: up)?|hurries(?: up)?", lambda m: w.set("gait", "run"))
    w.take(r"slow(?:s|ing)?(?: (?:it |them )?down| up)?|decelerat\w*|ease(?:s)? (?:off|up)(?: the gas)?|"
           r"(?:reduce|reduces"
           r"|lower|lowers|decrease|decreases|cut|cuts|drop|drops)(?: its| the| their)? speed|(?:go|goes|drive|"
           r"drives|move"
           r"|moves|walk|walks)(?: a (?:bit|little|lot))? slower|slower|slowly|brake|take it easy|coast|coasts|"
           r"lift off",
           lambda m: w.set("longitudinal", "decelerate") if "longitudinal" not in w.out.fields else None)
    w.take(r"speed(?:s|ing)? (?:it |them )?up|accelerat\w*|(?:go|goes|drive|drives|move|moves|walk|walks)"
           r"(?: a (?:bit|little|lot))? (?:faster|quicker)|faster|quicker|pick(?:s)? up (?:the )?(?:speed|pace)"
           r"|hurry(?: up)?|hurries(?: up)?|(?:step|steps) on (?:it|the gas)|floor it|put (?:the|its) foot down|gun it"
           r"|pull(?:s)? (?:out|away)|move(?:s)? off|(?:drive|drives|head|heads) (?:off|away)(?! (?:the|a|from) )"
           r"|increase (?:its |the )?speed",
           lambda m: w.set("longitudinal", "accelerate") if "longitudinal" not in w.out.fields else None)


def speed_change(behaviour: Behaviour, current: float, kind: AgentKind) -> float | None:
    """``accelerate``: a vehicle :data:`ACCELERATE_DELTA_MPS` faster; a pedestrian half as fast again, at least
    running when it walks faster than a walk (else one and a half walks). ``decelerate``: :data:`DECELERATE_FACTOR`
    of the pace (``gait.reference_pace``). Braking hard is a stop (no speed)."""
    base = reference_pace(current, kind)
    if behaviour.longitudinal == "accelerate":
        if kind == "vehicle":
            return base + ACCELERATE_DELTA_MPS
        return max(base * 1.5, RUN_MPS if base > WALK_MPS else WALK_MPS * 1.5)
    if behaviour.longitudinal == "decelerate":
        return base * DECELERATE_FACTOR
    return None


LONGITUDINAL = BehaviourDecl(
    "longitudinal",
    fields=("longitudinal",),
    intents=(
        Intent(
            "brake_hard",
            fields={"longitudinal": "brake_hard"},
            phrases=("brake hard", "slam on the brakes", "emergency stop"),
            family="slowing",
        ),
        Intent(
            "decelerate",
            fields={"longitudinal": "decelerate"},
            phrases=("slow down", "decelerate", "reduce speed"),
            family="slowing",
        ),
        Intent("accelerate", fields={"longitudinal": "accelerate"}, phrases=("speed up", "accelerate", "go faster")),
    ),
    motion_classes={voc.SLOWING_DOWN: "decelerate", voc.SPEEDING_UP: "accelerate"},
    proposal_forms={
        "hard_stop": (
            "Make {T} slam on the brakes.",
            "{T} should brake hard.",
            "Have {T} stop suddenly.",
            "Make {T} come to a sudden stop.",
            "{T} suddenly stops.",
        ),
    },
    prompt_forms={
        "vehicle_brake_hard": (
            "Make {T} brake hard.",
            "{T} should slam on the brakes.",
            "Have {T} do an emergency stop.",
        ),
        "vehicle_accelerate": (
            "Make {T} accelerate.",
            "{T} should speed up.",
            "Have {T} pick up speed.",
        ),
        "vehicle_decelerate": (
            "Make {T} slow down.",
            "{T} should decelerate.",
            "Have {T} reduce its speed.",
        ),
    },
    parse_rule=parse_longitudinal,
    speed_rule=speed_change,
)
