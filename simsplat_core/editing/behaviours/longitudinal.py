"""Braking hard, slowing down or speeding up without a said speed (``Behaviour.longitudinal``)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.scenario import vocabulary as voc

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
)
