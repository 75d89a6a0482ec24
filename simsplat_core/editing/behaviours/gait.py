"""Walking or running (pedestrians)."""

import re

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

#: Gait -> the verbs that say it (a regular-expression alternation).
GAIT_VERBS: dict[str, str] = {
    "run": r"run|runs|running|sprint|sprints|sprinting|jog|jogs|jogging|dash|dashes|race|races|rush|rushes|bolt|bolts",
    "walk": r"walk|walks|walking|stroll|strolls|strolling|amble|ambles|ambling|saunter|saunters|sauntering|wander"
            r"|wanders|wandering",
}
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
)
