"""Following another vehicle at a gap (vehicles; the leader is a ``TargetRef``)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent

FOLLOW = BehaviourDecl(
    "follow",
    fields=("follow",),
    agent="vehicle",
    words="following another vehicle",
    intents=(Intent("follow", phrases=("follow the car", "drive behind the car")),),
    motion_classes={},
    proposal_forms={},
    prompt_forms={},
)
