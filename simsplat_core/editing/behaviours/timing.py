"""Starting later: at a time, or a delay after the log's own start."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.editing.parse.speed import timing_rules

TIMING = BehaviourDecl(
    "timing",
    fields=("start_time_s", "delay_s"),
    intents=(Intent("wait", phrases=("wait before moving", "start later")),),
    motion_classes={},
    proposal_forms={
        "delay": (
            "Make {T} start {t} later.",
            "Have {T} start {t} later.",
        ),
        "ped_wait": (
            "Make {T} wait {t} before moving.",
            "{T} should start {t} later.",
        ),
    },
    prompt_forms={
        "vehicle_delay": (
            "Delay {T} by {t}.",
            "{T} should start {t} later.",
            "Let {T} wait {t} before moving.",
            "Make {T} set off {t} later than it does now.",
        ),
        "pedestrian_delay": (
            "Delay {T} by {t}.",
            "{T} should start walking {t} later.",
            "Let {T} wait {t} before walking.",
        ),
    },
    parse_rule=timing_rules,
)
