"""The registry of behaviours: every ``BehaviourDecl`` and the tables derived from them.

The parser (``editing.parse``), the motion requests (``editing.motion.requests``: who may do what, and the speed
asked, by the behaviours' speed rules in ``SPEED_ORDER``), the editing benchmark's
prompt wording (``eval.editing.wording``) and the mining rule client's wording (``mining.rule_wording``) read
these tables instead of spelling a behaviour's words themselves. ``BEHAVIOURS``' order is the order in which
the intents' phrasings are embedded (``editing.parse.semantic``); ``RESTRICTED``'s the order in which
agent-restricted fields are named in refusals.
"""

from __future__ import annotations

from typing import Any

from simsplat_core.editing.behaviours.cross_street import CROSS_STREET
from simsplat_core.editing.behaviours.declaration import BehaviourDecl
from simsplat_core.editing.behaviours.follow import FOLLOW
from simsplat_core.editing.behaviours.gait import GAIT
from simsplat_core.editing.behaviours.jaywalk import JAYWALK
from simsplat_core.editing.behaviours.lane_change import LANE_CHANGE
from simsplat_core.editing.behaviours.lateral_offset import LATERAL_OFFSET
from simsplat_core.editing.behaviours.longitudinal import LONGITUDINAL
from simsplat_core.editing.behaviours.reverse import REVERSE
from simsplat_core.editing.behaviours.speed import SPEED
from simsplat_core.editing.behaviours.stop import STOP
from simsplat_core.editing.behaviours.timing import TIMING
from simsplat_core.editing.behaviours.turn import TURN

#: Every behaviour of the edit language.
BEHAVIOURS: tuple[BehaviourDecl, ...] = (
    STOP, LONGITUDINAL, REVERSE, LANE_CHANGE, TURN, FOLLOW, CROSS_STREET, JAYWALK, GAIT, TIMING, SPEED, LATERAL_OFFSET,
)


#: The behaviours whose parser rules read a predicate, in the order they run (``editing.parse.behaviour``): each
#: rule blanks the words it used, so an earlier rule wins words two could read. The turn rule runs before the
#: speed rule ("do not turn" is not a negated speed); the street-crossing rule reads jaywalking's words too.
PARSE_ORDER: tuple[BehaviourDecl, ...] = (
    TURN, SPEED, TIMING, STOP, FOLLOW, LATERAL_OFFSET, REVERSE, LANE_CHANGE, CROSS_STREET, GAIT, LONGITUDINAL,
)
if {b.name for b in PARSE_ORDER} != {b.name for b in BEHAVIOURS if b.parse_rule is not None} \
        or len({b.name for b in PARSE_ORDER}) != len(PARSE_ORDER):
    raise ValueError("behaviour registry: PARSE_ORDER must list every behaviour with a parse rule once, and only those")

#: The behaviours with a speed rule, in precedence order (``editing.motion.requests.target_speed``: the first rule
#: that gives a speed wins): a said speed, then a gait, then speeding up / slowing down, then reversing, then a
#: standing person walking to cross.
SPEED_ORDER: tuple[BehaviourDecl, ...] = (SPEED, GAIT, LONGITUDINAL, REVERSE, CROSS_STREET)
if {b.name for b in SPEED_ORDER} != {b.name for b in BEHAVIOURS if b.speed_rule is not None} \
        or len({b.name for b in SPEED_ORDER}) != len(SPEED_ORDER):
    raise ValueError("behaviour registry: SPEED_ORDER must list every behaviour with a speed rule once, and only those")


def _unique(pairs: list[tuple[str, Any]], what: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"behaviour registry: {what} {key!r} is declared twice")
        out[key] = value
    return out


#: Intent -> the ``Behaviour`` field values it sets (intents with fixed values only).
INTENT_FIELDS: dict[str, dict[str, Any]] = _unique(
    [(i.name, i.fields) for b in BEHAVIOURS for i in b.intents if i.fields is not None], "intent")
#: Intent -> its imperative phrasings (E5 passages), in embedding order.
INTENT_PHRASES: dict[str, tuple[str, ...]] = _unique(
    [(i.name, i.phrases) for b in BEHAVIOURS for i in b.intents if i.phrases], "intent")
#: Intents close enough that E5 need not tell them apart -> their family.
INTENT_FAMILY: dict[str, str] = {i.name: i.family for b in BEHAVIOURS for i in b.intents if i.family is not None}
#: Scenario-vocabulary motion classes -> the intent of asking an agent to do it.
CLASS_INTENT: dict[str, str] = _unique([(c, i) for b in BEHAVIOURS for c, i in b.motion_classes.items()],
                                       "motion class")
#: The agent-restricted behaviours, in the order a refusal names them when a prompt asks several of the wrong
#: agent ("changing lanes or driving in reverse is not something a pedestrian does").
RESTRICTED: tuple[BehaviourDecl, ...] = (LANE_CHANGE, TURN, REVERSE, FOLLOW, CROSS_STREET, JAYWALK, GAIT)
if {b.name for b in RESTRICTED} != {b.name for b in BEHAVIOURS if b.agent is not None}:
    raise ValueError("behaviour registry: RESTRICTED must list every behaviour with an agent, and only those")


#: The behaviours the checks verify on the auto-labeller's motion class (``BehaviourDecl.label_check``), in the order
#: the benchmark's and the mining judge's checks report them.
LABEL_CHECKED: tuple[BehaviourDecl, ...] = tuple(b for b in BEHAVIOURS if b.label_check is not None)
#: Vehicle-only and pedestrian-only ``Behaviour`` fields.
VEHICLE_ONLY: tuple[str, ...] = tuple(f for b in RESTRICTED if b.agent == "vehicle" for f in b.fields)
PEDESTRIAN_ONLY: tuple[str, ...] = tuple(f for b in RESTRICTED if b.agent == "pedestrian" for f in b.fields)
#: Those fields in words, for messages.
FIELD_WORDS: dict[str, str] = {f: b.words for b in RESTRICTED for f in b.fields}
#: Mining rule client proposal kind -> sentence forms, of every behaviour.
PROPOSAL_FORMS: dict[str, tuple[str, ...]] = _unique(
    [(k, forms) for b in BEHAVIOURS for k, forms in b.proposal_forms.items()], "proposal kind")
#: Editing benchmark intent kind -> sentence forms, of every behaviour.
PROMPT_FORMS: dict[str, tuple[str, ...]] = _unique(
    [(k, forms) for b in BEHAVIOURS for k, forms in b.prompt_forms.items()], "prompt kind")

__all__ = ["BEHAVIOURS", "CLASS_INTENT", "FIELD_WORDS", "INTENT_FAMILY", "INTENT_FIELDS", "INTENT_PHRASES",
           "LABEL_CHECKED", "PARSE_ORDER", "PEDESTRIAN_ONLY", "PROMPT_FORMS", "PROPOSAL_FORMS", "RESTRICTED",
           "SPEED_ORDER", "VEHICLE_ONLY"]
