"""Stopping: at a time, before a crosswalk, intersection or stop line, or behind an object (``StopSpec``)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.editing.parse.speed import stop_rules
from simsplat_core.scenario import vocabulary as voc

STOP = BehaviourDecl(
    "stop",
    fields=("stop",),
    intents=(
        Intent(
            "stop",
            fields={"stop": {}},
            phrases=("stop", "come to a stop", "halt", "pull over and stop"),
            family="slowing",
        ),
    ),
    motion_classes={voc.STOPPING: "stop", voc.STOPPED: "stop", voc.PARKED: "stop", voc.STANDING: "stop"},
    proposal_forms={
        "ped_stop": (
            "Make {T} stop.",
            "Have {T} stop walking.",
        ),
    },
    prompt_forms={
        "vehicle_stop_crosswalk": (
            "Make {T} stop before the crosswalk.",
            "{T} should halt before the zebra crossing.",
            "Have {T} come to a stop in front of the pedestrian crossing.",
            "Stop {T} before it reaches the crosswalk.",
        ),
        "vehicle_stop": (
            "Make {T} come to a stop.",
            "{T} should pull up and stop.",
            "Bring {T} to a halt.",
        ),
        "vehicle_stop_by": (
            "Make {T} come to a complete stop within {t}.",
            "{T} should be standing still after {t}.",
            "Have {T} stop within {t}.",
        ),
        "pedestrian_stop": (
            "Make {T} stop.",
            "{T} should stop walking.",
            "Have {T} stand still.",
        ),
    },
    parse_rule=stop_rules,
)
