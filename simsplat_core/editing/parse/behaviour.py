"""What a predicate asks an agent to do: canonical words -> ``Behaviour`` fields.

    parse_predicate("slow down to 20 km/h and stop before the crosswalk", kind="vehicle").fields
    # {"speed": SpeedSpec(absolute, 20, km/h), "stop": {"before": "crosswalk"}}

Rules run in a fixed order on the canonical predicate (``editing.parse.text``): the op rule ("disappear"), then
each behaviour's own rule (``BehaviourDecl.parse_rule``, in ``editing.behaviours.registry.PARSE_ORDER``), then the
neutral words ("go on") and negation. Each blanks the words it used, so "stop behind the bus" is a stop, not also a
placement. What is left over (less filler words) is returned as ``residual``: the parser maps it with E5 or refuses
it, never drops it. When no rule matched, the grounding lexicon's motion keywords
(``grounding.lexicon.MOTION_KEYWORDS``) name a scenario-vocabulary class, which
``editing.behaviours.registry.CLASS_INTENT`` turns into an intent.

A given speed replaces accelerate / decelerate (not a hard brake).
"""

from __future__ import annotations

import re

from simsplat_core.editing.behaviours.registry import CLASS_INTENT, INTENT_FIELDS, PARSE_ORDER
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse.predicate import IGNORABLE, PredicateParse, PredicateWork
from simsplat_core.language.grounding.lexicon import MOTION_KEYWORDS

__all__ = ["PredicateParse", "keyword_intent", "parse_predicate"]


def _op_rules(w: PredicateWork) -> None:
    if w.take(r"disappear|disappears|vanish|vanishes|go away|goes away|be (?:removed|deleted|gone|erased)|leave the "
              r"(?:scene|road|picture)|get (?:out|off) (?:of )?the (?:scene|road)|cease to exist|be taken out"):
        w.out.op = "remove"


def _neutral_rules(w: PredicateWork) -> None:
    w.take(r"than (?:now|before|it (?:is|was)|it does now|currently|usual|normal|normally|in the log|originally"
           r"|its current speed|the others?|other cars)|towards? (?:us|me|the ego(?: vehicle| car)?)|the other way"
           r"|in the opposite direction|against (?:the )?traffic", repeat=True)
    if w.take(r"go|goes|drive|drives|move|moves|continue|continues|proceed|proceeds|keep going|carry on|keep driving"
              r"|resume|resumes|start moving|get going|go on|drive on|move on|set off|ride|rides|riding|cycling"
              r"|biking|cycle|cycles", repeat=True):
        w.out.neutral = True


def _negation(w: PredicateWork) -> None:
    if re.search(r"(?<![\w-])(?:do not|does not|not|never|no longer|no)(?![\w-])", w.text):
        w.out.refusal = w.out.refusal or "negated edits ('do not ...') are not supported: say what should happen"


def parse_predicate(text: str, kind: str | None = None) -> PredicateParse:
    """Behaviour fields of a canonical predicate (module docstring).

    Args:
        text: canonical predicate words ("slow down to 20 km/h").
        kind: ``"vehicle"`` / ``"pedestrian"`` / ``"static"`` / ``None`` -- only changes "hurry" (a pedestrian
            runs, a vehicle accelerates).
    """
    w = PredicateWork(text, kind)
    _op_rules(w)
    for behaviour in PARSE_ORDER:
        assert behaviour.parse_rule is not None  # the registry checks it
        behaviour.parse_rule(w)
    _neutral_rules(w)
    _negation(w)
    out = w.out
    if "speed" in out.fields and out.fields.get("longitudinal") in ("accelerate", "decelerate"):
        del out.fields["longitudinal"]
    out.residual = " ".join(t for t in w.text.split() if "|" not in t and t not in IGNORABLE
                            and not (t.endswith("ly") and len(t) > 4) and t not in chunks.PUNCT)
    if not (out.fields or out.refs or out.op or out.refusal):
        intent = keyword_intent(text)
        if intent is not None:
            out.fields.update(INTENT_FIELDS[intent])
            out.residual = ""
    return out


def keyword_intent(text: str) -> str | None:
    """The intent the grounding lexicon's motion keywords give a phrase ("hit the brakes" -> decelerate), when
    every class they name means the same intent; else ``None``."""
    intents = {CLASS_INTENT[c] for rx, classes in MOTION_KEYWORDS if re.search(rx, text) for c in classes}
    return intents.pop() if len(intents) == 1 else None
