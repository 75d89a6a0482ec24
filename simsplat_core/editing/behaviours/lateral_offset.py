"""A sideways shift of the own path, metres (+ = left)."""

from simsplat_core.editing.behaviours.declaration import BehaviourDecl

LATERAL_OFFSET = BehaviourDecl(
    "lateral_offset",
    fields=("lateral_offset_m",),
    intents=(),
    motion_classes={},
    proposal_forms={},
    prompt_forms={},
)
