"""What a predicate asks an agent to do: canonical words -> ``Behaviour`` fields.

    parse_predicate("slow down to 20 km/h and stop before the crosswalk", kind="vehicle").fields
    # {"speed": SpeedSpec(absolute, 20, km/h), "stop": {"before": "crosswalk"}}

Rules run in a fixed order on the canonical predicate (``editing.parse.text``); each blanks the words it used, so
"stop behind the bus" is a stop, not also a placement. What is left over (less filler words) is returned as
``residual``: the parser maps it with E5 or refuses it, never drops it. When no rule matched, the grounding
lexicon's motion keywords (``grounding.lexicon.MOTION_KEYWORDS``) name a scenario-vocabulary class, which
``editing.behaviours.registry.CLASS_INTENT`` turns into an intent.

Speeds, stops and timing are read by ``editing.parse.speed``; a given speed replaces accelerate / decelerate (not
a hard brake).
"""

from __future__ import annotations

import re

from simsplat_core.editing.behaviours.registry import CLASS_INTENT, INTENT_FIELDS
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse.predicate import IGNORABLE, PredicateParse, PredicateWork
from simsplat_core.editing.parse.speed import speed_rules, stop_rules, timing_rules
from simsplat_core.language.grounding.lexicon import MOTION_KEYWORDS
from simsplat_core.scenario import vocabulary as voc

__all__ = ["PredicateParse", "keyword_intent", "parse_predicate"]

_N = r"(\d+(?:\.\d+)?)"
_CROSSABLE = (r"(?: over)?(?: (?:the|a) (?:street|road|lane|lanes|carriageway|crosswalk|zebra crossing|"
              + voc.INTERSECTION_RX + r"))?")
#: Where a turn is made ("at the crossroads", "through the next crossing"): words that add nothing to it.
_TURN_PLACE = (r"(?:at|in|into|through|across|on|by) (?:the |a )?(?:next |first |upcoming |coming |nearest )?"
               r"(?:" + voc.INTERSECTION_RX + r"|crossing)")
#: Where a car reverses out of ("out of its parking space"): words that add nothing to the reversing.
_OUT_OF_SPOT = (r"(?: out)?(?: of (?:its|the|his|her|their|a) (?:parking )?(?:spot|space|bay|place|slot|driveway|"
                r"parking))?")
_AMBIGUOUS_LANE = r"\b(?:change|changes|changing|switch|switches|swap|swaps)(?: the)? lanes?\b|\blane[- ]change\b"


def _lateral_rules(w: PredicateWork) -> None:
    def reverse(m: re.Match[str]) -> None:
        w.set("reverse", True)

    w.take(r"(?:shift|shifts|move|moves|nudge|nudges|slide|slides|offset|drift|drifts|steer|steers)(?: it| over|"
           r" sideways)?"
           r" " + _N + r" m (?:to the |towards the |over to the |to its )?(left|right)",
           lambda m: w.set("lateral_offset_m", float(m.group(1)) * (1 if m.group(2) == "left" else -1)))
    w.take(r"(?:reverse|reverses|reversing|back(?:s|ing)? (?:up|out|it up)|back up|(?:drive|drives|go|goes|move|moves"
           r"|roll|rolls|head|heads|travel|travels)(?: it)? backwards?|(?:in|into) reverse(?: gear)?)" + _OUT_OF_SPOT,
           reverse)

    def lane(m: re.Match[str]) -> None:
        w.set("lane_change", m.group(1))

    verbs = (r"(?:change|changes|changing|switch|switches|shift|shifts|move|moves|merge|merges|cut|cuts|swerve|swerves"
             r"|veer|veers|pull|pulls|hop|hops|slide|slides|drift|drifts|steer|steers|squeeze|squeezes|nudge|nudges)")
    w.take(verbs + r"(?: over| across| in| back)?(?: (?:a |one )?lanes?)?(?: (?:to|into|in to|onto|towards|"
                   r"toward|over to"
           r"|across to|in)(?: the)?)? (left|right)(?:[- ]hand)?(?: side)?(?: lane)?", lane)
    w.take(r"(?:(?:turn|turns|go|goes|get|gets|head|heads|drive|drives|pull|pulls|come|comes)(?: over)? )?"
           r"(?:into|to|in to|onto|over to) the (left|right)(?:[- ]hand)? lane|lane[- ]change (?:to the )?(left|right)"
           r"|(left|right) lane[- ]change", lambda m: w.set("lane_change", next(g for g in m.groups() if g)))
    if w.take(r"(?:overtake|overtakes|overtaking|pass|passes|passing|get past|gets past|go around|goes around)"):
        w.set("lane_change", "left")
        w.set("longitudinal", "accelerate")
        start = w.text.rfind("|") + 1
        phrase, end = w.noun_phrase_after(start)
        if phrase:
            w.blank(start, end)
    if "lane_change" not in w.out.fields and re.search(_AMBIGUOUS_LANE, w.text):
        w.out.refusal = "a lane change needs a side: say 'change lanes to the left' or 'to the right'"
        w.out.refusal_field = "lane_change"
        w.take(_AMBIGUOUS_LANE)


#: "... straight instead of turning (left)": the turn given up is part of the go-straight phrase.
_NOT_TURNING = (r"(?:,? (?:instead of|rather than|and not)(?: (?:making|taking|doing))?(?: (?:a|an|the|its|their))?"
                r"(?: (?:left|right)(?:[- ]hand)?)? turn(?:ing|s)?(?: (?:off )?(?:to the )?(?:left|right)"
                r"(?:[- ]hand)?)?)?")


def _turn_rules(w: PredicateWork) -> None:
    if w.take(r"u[- ]?turn|u[- ]?turns|turn(?:s)? (?:it |them )?(?:around|back)|do a 180|pull a 180"):
        w.out.refusal = "U-turns are not supported (turn left or right, or go straight, at the next intersection)"
        w.out.refusal_field = "turn"
    w.take(r"(?:(?:do not|does not|not|never|no|without) turn(?:ing)?(?: (?:left|right))?"
           r"|(?:go|goes|going|drive|drives|driving|continue"
           r"|continues|continuing|keep|keeps|keep going|keep driving|carry on|carries on|head|heads|proceed|proceeds"
           r"|stay|stays|travel|travels|run)(?: on)? straight(?: on| ahead| through| across)?|"
           r"straight (?:through|across"
           r"|on|ahead))" + _NOT_TURNING, lambda m: w.set("turn", "straight"))
    w.take(r"(?:turn|turns|turning|hang|hangs|take|takes|make|makes|swing|swings|bear|bears|go|goes|head|heads|hook"
           r"|hooks)(?: off)?(?: a| an| the)?(?: (?:next|first|upcoming))? (?:to the )?(left|right)(?:[- ]hand)?"
           r"(?: turn)?(?! lane)|(left|right)(?:[- ]hand)? turn",
           lambda m: w.set("turn", m.group(1) or m.group(2)))
    if "turn" in w.out.fields:  # where the turn is made: a "crossing" there is the intersection, not a crosswalk
        w.take(_TURN_PLACE)


def _pedestrian_rules(w: PredicateWork) -> None:
    jay = (r"away from (?:the |any )?(?:crosswalk|zebra(?: crossing)?)|mid[- ]?block|not (?:at|on|using|"
           r"via) (?:the |a )?"
           r"(?:crosswalk|zebra(?: crossing)?)|in the middle of the (?:road|street|block)|outside (?:of )?(?:the |a )?"
           r"(?:crosswalk|zebra(?: crossing)?)|illegally|without (?:using )?(?:the |a )?(?:crosswalk|"
           r"zebra(?: crossing)?)"
           r"|where there is no (?:crosswalk|zebra)")
    jaywalking = w.take(r"jaywalk\w*(?: (?:across|over))?(?: (?:the|a) (?:street|road))?") | w.take(jay)
    gaits = {"run": r"run|runs|running|sprint|sprints|sprinting|jog|jogs|jogging|dash|dashes|race|races|rush|rushes"
                    r"|bolt|bolts",
             "walk": r"walk|walks|walking|stroll|strolls|strolling|amble|ambles|ambling|saunter|saunters|sauntering"
                     r"|wander|wanders|wandering"}
    start = r"(?:(?:start|starts|begin|begins|break|breaks) (?:to |into a )?)?"  # "start running"
    about_to = r"(?:(?:" + "|".join(sorted(chunks.TO_KEEPERS)) + r") to )?"  # "waiting to cross"
    crossed = w.take(about_to + r"(?:(?:cross|crosses|crossing)" + _CROSSABLE + r"|(?:(?:" + gaits["run"] + "|"
                     + gaits["walk"]
                     + r"|go|goes|head|heads|step|steps|hurry|hurries|make (?:his|her|their|"
                       r"its) way)(?: out)? (?:across"
                     r"|over)(?: (?:the )?(?:street|road|lane|lanes|carriageway))?))"
                     r"(?: (?:at|on|using|via|along) (?:the |a )?(?:crosswalk|zebra(?: crossing)?|"
                     r"pedestrian crossing))?",
                     lambda m: _gait_of(w, m.group(0), gaits))
    if crossed or jaywalking:
        w.set("cross_street", True)
    if jaywalking:
        w.set("jaywalk", True)
    if "gait" not in w.out.fields:
        w.take(start + r"(?:" + gaits["run"] + r")", lambda m: w.set("gait", "run"))
    if "gait" not in w.out.fields:
        w.take(start + r"(?:" + gaits["walk"] + r")", lambda m: w.set("gait", "walk"))


def _gait_of(w: PredicateWork, phrase: str, gaits: dict[str, str]) -> None:
    for gait, rx in gaits.items():
        if re.match(r"(?:" + rx + r")\b", phrase):
            w.set("gait", gait)


def _longitudinal_rules(w: PredicateWork) -> None:
    if w.kind == "pedestrian":
        w.take(r"hurry(?: up)?|hurries(?: up)?", lambda m: w.set("gait", "run"))
    w.take(r"slow(?:s|ing)?(?: (?:it |them )?down| up)?|decelerat\w*|ease(?:s)? (?:off|up)(?: the gas)?|"
           r"(?:reduce|reduces"
           r"|lower|lowers|decrease|decreases|cut|cuts|drop|drops)(?: its| the| their)? speed|(?:go|goes|drive|"
           r"drives|move"
           r"|moves|walk|walks)(?: a (?:bit|little|lot))? slower|slower|slowly|brake|take it easy|coast|coasts|"
           r"lift off",
           lambda m: w.set("longitudinal", "decelerate") if "longitudinal" not in w.out.fields else None)
    w.take(r"speed(?:s|ing)? (?:it |them )?up|accelerat\w*|(?:go|goes|drive|drives|move|moves|walk|walks)"
           r"(?: a (?:bit|little|lot))? (?:faster|quicker)|faster|quicker|pick(?:s)? up (?:the )?(?:speed|pace)"
           r"|hurry(?: up)?|hurries(?: up)?|(?:step|steps) on (?:it|the gas)|floor it|put (?:the|its) foot down|gun it"
           r"|pull(?:s)? (?:out|away)|move(?:s)? off|(?:drive|drives|head|heads) (?:off|away)(?! (?:the|a|from) )"
           r"|increase (?:its |the )?speed",
           lambda m: w.set("longitudinal", "accelerate") if "longitudinal" not in w.out.fields else None)


def _follow_rules(w: PredicateWork) -> None:
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
    _turn_rules(w)  # before speeds: "do not turn" is not a negated speed
    speed_rules(w)
    timing_rules(w)
    stop_rules(w)
    _follow_rules(w)
    _lateral_rules(w)
    _pedestrian_rules(w)
    _longitudinal_rules(w)
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
