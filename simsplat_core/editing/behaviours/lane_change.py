"""Changing into the neighbour lane on a side (vehicles; the benchmark also asks it of pedestrians, to be refused)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.scenario import vocabulary as voc

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
)
