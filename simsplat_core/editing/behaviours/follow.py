"""Following another vehicle at a gap (vehicles; the leader is a ``TargetRef``)."""

import re

from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent
from simsplat_core.editing.parse.predicate import PredicateWork


def parse_follow(w: PredicateWork) -> None:
    """"follow / tailgate / drive behind <noun phrase>" -> ``refs["follow"]``: the leader, grounded later."""
    for m in re.finditer(r"(?<![\w-])(?:follow|follows|following|tailgate|tailgates|tailgating|trail|trails|"
                         r"chase|chases"
                         r"|shadow|shadows|pursue|pursues|tail|tails|go after|goes after|drive behind|drives behind"
                         r"|stay behind|stays behind|keep behind|keeps behind|get behind|gets behind|queue behind"
                         r"|line up behind|stick behind|stick to|keep following)(?= )", w.text):
        phrase, end = w.noun_phrase_after(m.end(), exclude=("behind",))
        if phrase:
            w.out.refs["follow"] = phrase
            w.blank(m.start(), end)
            return


FOLLOW = BehaviourDecl(
    "follow",
    fields=("follow",),
    agent="vehicle",
    words="following another vehicle",
    intents=(Intent("follow", phrases=("follow the car", "drive behind the car")),),
    motion_classes={},
    proposal_forms={},
    prompt_forms={},
    parse_rule=parse_follow,
)
