"""Walking or running (pedestrians): the words, and the paces walking and running mean."""

import re

from simsplat_core.editing.behaviours.declaration import AgentKind, BehaviourDecl, Intent
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

#: Gait -> the verbs that say it (a regular-expression alternation).
GAIT_VERBS: dict[str, str] = {
    "run": r"run|runs|running|sprint|sprints|sprinting|jog|jogs|jogging|dash|dashes|race|races|rush|rushes|bolt|bolts",
    "walk": r"walk|walks|walking|stroll|strolls|strolling|amble|ambles|ambling|saunter|saunters|sauntering|wander"
            r"|wanders|wandering",
}
#: Pedestrian gaits, m/s.
WALK_MPS = 1.4
RUN_MPS = 3.0
#: A pedestrian slower than this stands, m/s (a standing person's pace is a walk).
STANDING_MPS = 0.3
#: "*start* running": words before a gait verb that add nothing to it.
_START = r"(?:(?:start|starts|begin|begins|break|breaks) (?:to |into a )?)?"


def set_gait_of(w: PredicateWork, phrase: str) -> None:
    """Set ``gait`` from the verb ``phrase`` starts with ("sprint across the road" -> run), if it is a gait verb."""
    for gait, rx in GAIT_VERBS.items():
        if re.match(r"(?:" + rx + r")\b", phrase):
            w.set("gait", gait)


def parse_gait(w: PredicateWork) -> None:
    """"run", "start jogging", "stroll" -> ``gait`` (unless the street-crossing rule already read one)."""
    if "gait" not in w.out.fields:
        w.take(_START + r"(?:" + GAIT_VERBS["run"] + r")", lambda m: w.set("gait", "run"))
    if "gait" not in w.out.fields:
        w.take(_START + r"(?:" + GAIT_VERBS["walk"] + r")", lambda m: w.set("gait", "walk"))


def reference_pace(current: float, kind: AgentKind) -> float:
    """The speed a relative speed ("twice as fast", "slow down") is taken against, m/s: a vehicle's ``current``
    |speed|; a pedestrian's, or :data:`WALK_MPS` when it stands (below :data:`STANDING_MPS`)."""
    if kind == "pedestrian" and current <= STANDING_MPS:
        return WALK_MPS
    return current


def gait_speed(behaviour: Behaviour, current: float, kind: AgentKind) -> float | None:
    """Running :data:`RUN_MPS`, walking :data:`WALK_MPS`."""
    if behaviour.gait is None:
        return None
    return RUN_MPS if behaviour.gait == "run" else WALK_MPS


GAIT = BehaviourDecl(
    "gait",
    fields=("gait",),
    agent="pedestrian",
    words="walking or running",
    intents=(
        Intent("run", fields={"gait": "run"}, phrases=("run", "walk fast")),
        Intent("walk", fields={"gait": "walk"}, phrases=("walk",)),
    ),
    motion_classes={voc.WALKING_ALONG: "walk"},
    proposal_forms={
        "ped_run": (
            "Make {T} run.",
            "{T} should jog.",
            "Have {T} sprint.",
        ),
    },
    prompt_forms={
        "pedestrian_run": (
            "Make {T} run.",
            "{T} should start running.",
            "Have {T} jog instead of walking.",
        ),
    },
    parse_rule=parse_gait,
    speed_rule=gait_speed,
)
