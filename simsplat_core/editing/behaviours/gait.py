"""Walking or running (pedestrians)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.scenario import vocabulary as voc

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
)
