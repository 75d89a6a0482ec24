"""What a predicate asks an agent to do: canonical words -> ``Behaviour`` fields.

    parse_predicate("slow down to 20 km/h and stop before the crosswalk", kind="vehicle").fields
    # {"speed": SpeedSpec(absolute, 20, km/h), "stop": {"before": "crosswalk"}}

Rules run in a fixed order on the canonical predicate (``parser_text``); each blanks the words it used, so
"stop behind the bus" is a stop, not also a placement. What is left over (less filler words) is returned as
``residual``: the parser maps it with E5 or refuses it, never drops it. When no rule matched, the grounding
lexicon's motion keywords (``query_lexicon.MOTION_KEYWORDS``) name a scenario-vocabulary class, which
``parser_lexicon.CLASS_INTENT`` turns into an intent.

Speeds: absolute ("40 km/h", "at 15 m/s"; a bare number after a speed verb is km/h), factor ("twice as
fast", "half the speed", "three times faster", "50 % faster" -> 1.5) or delta ("10 km/h slower" -> -10,
"speed up by 5 mph"). A given speed replaces accelerate / decelerate (not a hard brake).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from simsplat_core.editing import parser_chunks as chunks
from simsplat_core.editing.commands import SpeedSpec
from simsplat_core.editing.parser_lexicon import CLASS_INTENT
from simsplat_core.editing.parser_text import number_word
from simsplat_core.language.query_lexicon import MOTION_KEYWORDS

_N = r"(\d+(?:\.\d+)?)"
_SPEED = _N + r" (km/h|m/s|mph)"
_CROSSABLE = (r"(?: over)?(?: (?:the|a) (?:street|road|lane|lanes|carriageway|intersection|crosswalk|zebra crossing"
              r"|junction))?")
_STOP_PLACES = (r"(crosswalk|zebra crossing|zebra|pedestrian crossing|crossing|intersection|junction|crossroads?"
                r"|stop line|stop sign|traffic lights?|lights?|red light|signal)")

#: Behaviour fields each intent sets (``stop`` is a dict of ``StopSpec`` fields).
INTENT_FIELDS: dict[str, dict[str, Any]] = {
    "stop": {"stop": {}}, "brake_hard": {"longitudinal": "brake_hard"}, "decelerate": {"longitudinal": "decelerate"},
    "accelerate": {"longitudinal": "accelerate"}, "reverse": {"reverse": True}, "lane_left": {"lane_change": "left"},
    "lane_right": {"lane_change": "right"}, "turn_left": {"turn": "left"}, "turn_right": {"turn": "right"},
    "straight": {"turn": "straight"}, "cross": {"cross_street": True},
    "jaywalk": {"jaywalk": True, "cross_street": True},
    "walk": {"gait": "walk"}, "run": {"gait": "run"},
}
#: Words a predicate may hold that say nothing on their own.
IGNORABLE = frozenset(
    "the a an its their his her it them they to at in on of and then also just now right away instead again bit "
    "little lot much very really next first upcoming coming nearest intersection junction lane road street there "
    "here be get is are will should must can could would may might shall as same time possible way that which who "
    "so soon please up down its own current please some more for with when while immediately straight ahead "
    "forward moving driving walking going travelling traveling running motion too well rather quite please "
    "completely entirely fully safely smoothly gradually gently normally please scene sequence clip log video "
    "from by through until till this these those one ones okay ok mode ego us me our my you your fast slow "
    "car vehicle pedestrian person please side curb kerb roadside having had has have do does did".split()
)
_AMBIGUOUS_LANE = r"\b(?:change|changes|changing|switch|switches|swap|swaps)(?: the)? lanes?\b|\blane[- ]change\b"


@dataclass
class PredicateParse:
    """What a predicate asked for.

    Attributes:
        fields: ``Behaviour`` field values (``stop``: dict of ``StopSpec`` fields, ``behind`` left out).
        refs: noun phrases the behaviour points at: ``"follow"`` (the leader), ``"stop_behind"``.
        op: ``"remove"`` when the predicate means removal ("disappear").
        refusal: why the predicate cannot be done even though it was understood ("U-turns ...").
        refusal_field: the ``Behaviour`` field the refused request is about (for the category check).
        residual: words no rule used (filler removed); ``""`` when everything was understood.
        neutral: the predicate only says "go on" ("drive", "continue").
    """

    fields: dict[str, Any] = field(default_factory=dict)
    refs: dict[str, str] = field(default_factory=dict)
    op: str | None = None
    refusal: str | None = None
    refusal_field: str | None = None
    residual: str = ""
    neutral: bool = False

    @property
    def understood(self) -> bool:
        return bool(self.fields or self.refs or self.op or self.refusal or self.neutral)


class _Work:
    """A predicate being read: the text with used words blanked, and what was found."""

    def __init__(self, text: str, kind: str | None) -> None:
        self.text = f" {text} "
        self.kind = kind
        self.out = PredicateParse()

    def take(self, rx: str, fn: Callable[[re.Match[str]], Any] | None = None, repeat: bool = False) -> bool:
        """Apply ``fn`` to the first (or every) match of ``rx`` and blank it; whether anything matched."""
        found = False
        for m in list(re.finditer(r"(?<![\w/-])(?:" + rx + r")(?![\w/-])", self.text)):
            if "|" in m.group(0):  # overlaps a phrase already used
                continue
            if fn is not None and fn(m) is False:
                continue
            self.blank(m.start(), m.end())
            found = True
            if not repeat:
                break
        return found

    def blank(self, start: int, end: int) -> None:
        self.text = self.text[:start] + " " + "|" * max(end - start - 2, 1) + " " + self.text[end:]

    def noun_phrase_after(self, end: int, exclude: tuple[str, ...] = ()) -> tuple[str, int]:
        """The noun phrase starting after character ``end`` (text, its end character); ``("", end)``: none."""
        rest = self.text[end:]
        tokens = rest.split()
        if not tokens or "|" in tokens[0]:
            return "", end
        stop = chunks.chunk_np(tokens, 0, "target", exclude=("at", "after", "before", "until", "for", "with",
                                                             "in", "by", *exclude))
        if stop == 0:
            return "", end
        phrase = " ".join(tokens[:stop])
        return phrase, end + rest.index(phrase) + len(phrase)

    def set(self, name: str, value: Any) -> None:
        self.out.fields[name] = value

    def stop(self, **values: Any) -> None:
        self.out.fields.setdefault("stop", {}).update(values)


def _factor(word: str) -> float | None:
    table = {"twice": 2.0, "double": 2.0, "doubles": 2.0, "triple": 3.0, "triples": 3.0, "thrice": 3.0,
             "quadruple": 4.0, "half": 0.5, "halve": 0.5, "halves": 0.5}
    return table.get(word, number_word(word))


def _speed_rules(w: _Work) -> None:
    def factor(value: float | None) -> bool:
        if value is None:
            return False
        w.set("speed", SpeedSpec(mode="factor", value=round(value, 4)))
        return True

    faster = r"(?:faster|quicker|more)"
    slower = r"(?:slower|less)"
    up = (r"(?:speed(?:s)? up|accelerate(?:s)?|increase(?:s)? (?:its |the |their )?speed|go(?:es)? faster|faster|"
          r"quicker"
          r"|pick(?:s)? up speed|boost(?:s)? (?:its |the )?speed)")
    down = (r"(?:slow(?:s)? down|slow(?:s)?|decelerate(?:s)?|(?:reduce|lower|decrease|cut|drop)(?:s)? (?:its |"
            r"the |their )?"
            r"speed|go(?:es)? slower|slower|brake(?:s)?|ease(?:s)? off)")
    w.take(r"(?:at |to |go |drive |move |walk )?(twice|double|triple|thrice|quadruple|half)(?: as (?:fast|quick(?:ly)?)"
           r"| (?:the |its |their )?(?:current |original |normal |usual )?speed)",
           lambda m: factor(_factor(m.group(1))))
    w.take(r"(double|triple|halve|quadruple)s? (?:its |the |their )?speed", lambda m: factor(_factor(m.group(1))))
    w.take(r"(\d+(?:\.\d+)?|\w+) times (?:as fast|as quick(?:ly)?|faster|quicker|the speed|(?:its|the|their) "
           r"(?:current )?speed)", lambda m: factor(_factor(m.group(1))))
    w.take(_N + r" % " + faster, lambda m: factor(1 + float(m.group(1)) / 100))
    w.take(_N + r" % " + slower, lambda m: factor(max(0.0, 1 - float(m.group(1)) / 100)))
    w.take(up + r"(?: by)? " + _N + r" %", lambda m: factor(1 + float(m.group(1)) / 100))
    w.take(down + r"(?: by)? " + _N + r" %", lambda m: factor(max(0.0, 1 - float(m.group(1)) / 100)))
    w.take(r"(?:at |to |with )?" + _N + r" % (?:of )?(?:its |the |their )?(?:current |original |normal |usual )?speed",
           lambda m: factor(float(m.group(1)) / 100))

    def delta(m: re.Match[str], sign: float, value: int = 1, unit: int = 2) -> None:
        w.set("speed", SpeedSpec(mode="delta", value=sign * float(m.group(value)),
                                 unit=m.group(unit)))  # type: ignore[arg-type]

    w.take(_SPEED + r" " + faster, lambda m: delta(m, 1.0))
    w.take(_SPEED + r" " + slower, lambda m: delta(m, -1.0))
    w.take(up + r"(?: by)? " + _SPEED, lambda m: delta(m, 1.0))
    w.take(down + r"(?: by)? " + _SPEED, lambda m: delta(m, -1.0))
    w.take(r"(?:faster|quicker) by " + _SPEED, lambda m: delta(m, 1.0))
    w.take(r"slower by " + _SPEED, lambda m: delta(m, -1.0))

    def absolute(value: str, unit: str, words: str = "") -> bool:
        w.set("speed", SpeedSpec(mode="absolute", value=float(value), unit=unit))  # type: ignore[arg-type]
        gait = re.search(r"\b(walk|run)s?\b", words)
        if gait:
            w.set("gait", gait.group(1))
        return True

    lead = (r"(?:(?:at|to|with|of|reach|reaches|hit|hits|doing|do|does|maintain|maintains|keep|hold|a|an|constant"
            r"|steady|top|speed|up|down|limit|exactly|only|just|the|going|go|goes|drive|drives|travel|travels|cruise"
            r"|move|moves|walk|walks|run|runs) )*")
    w.take(lead + _SPEED, lambda m: absolute(m.group(1), m.group(2), m.group(0)))
    w.take(r"(?:(?:go|goes|drive|drives|travel|travels|cruise|cruises|move|moves|speed up|accelerate|accelerates"
           r"|slow down|slow|slows down|decelerate|decelerates|brake|brakes)(?: down| up)? (?:at|to) |(?:a )?speed of )"
           + _N + r"(?! (?:m|s|%|deg)\b)", lambda m: absolute(m.group(1), "km/h"))


def _stop_rules(w: _Work) -> None:
    def hard(m: re.Match[str]) -> None:
        w.set("longitudinal", "brake_hard")
        if re.search(r"stop", m.group(0)):
            w.stop()

    w.take(r"(?:brake|brakes|braking) (?:really |very )?(?:hard|sharply|suddenly|abruptly|heavily|violently|fast)"
           r"|(?:slam|slams|jam|jams|stomp|stomps|stand|stands)(?: on)? (?:the|its|their) brakes?|hard brak\w*"
           r"|emergency (?:brake|braking|stop)|(?:hit|hits|hitting) the brakes hard|full brak\w*|panic stop"
           r"|(?:brake|stop) as hard as (?:it can|possible)|do an emergency stop|stop (?:suddenly|abruptly|hard)", hard)
    stopped = w.take(
        r"(?:come|comes|coming|bring|brake|brakes|pull|pulls|roll|rolls|slow|slows|grind|grinds|glide|glides)"
        r"(?: down| up| itself)? to a (?:complete |full |dead |gentle |smooth |sudden |quick )?(?:stop|halt|standstill)"
        r"|(?:stop|stops|stopping|halt|halts|pull over|pulls over|pull up|pulls up|park|parks|freeze|freezes"
        r"|stand still|stay still|stays still|stay put|keep still|remain still|remain stationary|stay stationary"
        r"|stop moving|cease moving|yield|yields|give way|gives way|wait|waits)(?! sign| line)", lambda m: w.stop(),
        repeat=True) or "stop" in w.out.fields
    if not stopped:
        return
    w.take(r"(?:at|after|in|within|by|around) " + _N + r" s|" + _N + r" s (?:later|from now|into the \w+)",
           lambda m: w.stop(at_time_s=float(m.group(1) or m.group(2))))

    def before(m: re.Match[str]) -> None:
        place = m.group(2)
        kind = ("crosswalk" if re.match(r"cross|zebra|pedestrian", place) and "crossroad" not in place
                else "intersection" if re.match(r"inter|junc|crossroad", place) else "stop_line")
        w.stop(before=kind, **({"gap_m": float(m.group(1))} if m.group(1) else {}))

    w.take(r"(?:" + _N + r" m )?(?:right |just |directly )?(?:before|at|short of|in front of|ahead of|prior to|by"
           r"|near|for|behind|ahead)? ?(?:the |a )?(?:next |upcoming |first |nearest |coming )?" + _STOP_PLACES, before)
    for m in re.finditer(r"(?:(\d+(?:\.\d+)?) m )?(?:right |directly |just |close )?(?:behind|in back of|back of"
                         r"|after)(?= )", w.text):
        if "|" in m.group(0):
            continue
        phrase, end = w.noun_phrase_after(m.end())
        if phrase and not chunks.is_quantity(phrase.split(), 0):
            w.out.refs["stop_behind"] = phrase
            if m.group(1):
                w.stop(gap_m=float(m.group(1)))
            w.blank(m.start(), end)
            break
    w.take(r"(?:with |leaving |keeping )?(?:a )?(?:gap|distance|space) of " + _N + r" m|(?:with |leaving |keeping )"
           r"(?:a )?" + _N + r" m (?:gap|distance|space)", lambda m: w.stop(gap_m=float(m.group(1) or m.group(2))))


def _timing_rules(w: _Work) -> None:
    go = (r"(?:start|starts|leave|leaves|depart|departs|begin|begins|set off|sets off|go|goes|move|moves|arrive"
          r"|arrives|appear|appears|come|comes|pull away|pulls away|get going|gets going|enter|enters|drive|drives"
          r"|walk|walks)(?: (?:moving|driving|walking|off|out|to move|to drive|to walk))?")
    w.take(go + r" " + _N + r" s (?:later|late|behind(?: schedule)?)|" + _N + r" s (?:later|late|of delay|delay|"
                                                                              r"delayed)"
           r"|(?:delay|delays|delayed|postpone|postpones|postponed|hold back|holds back|push back|pushes back)"
           r"(?: (?:it|its start|the start|their start|its departure|start|them))?(?: by| for)? " + _N + r" s"
           r"|with a " + _N + r" s delay|(?:a )?delay of " + _N + r" s",
           lambda m: w.set("delay_s", float(next(g for g in m.groups() if g))))
    w.take(r"before(?= (?:crossing|cross|it crosses|they cross|walking))")
    then_go = (r"(?: (?:before|then|and then|until|and)(?: it| they| he| she)? (?:moving|driving|going|starting"
               r"|starts|start|moves|move|goes|go|drives|drive|walks|walk|leaving|leaves|pulling away|setting off"
               r"|sets off|start(?:ing|s)? (?:to move|moving|driving|walking|off)))?")
    w.take(r"(?:wait|waits|pause|pauses|hold|holds|hold on|hold still|stay put|stay still|stand still|remain still"
           r"|remain stationary|idle|idles|do not move|not move|stay stationary|sit|sits|stay|stays)(?: there)?"
           r"(?: for)? " + _N + r" s" + then_go, lambda m: w.set("start_time_s", float(m.group(1))))
    w.take(go + r" (?:at|after|from|in) " + _N + r" s|(?:only )?after " + _N + r" s(?: ,)? (?:start|move|go|drive|walk)"
           r"|(?:do not|not) (?:move|start|go|leave|drive)(?: moving)? (?:until|before|till|for(?: the first)?) " + _N
           + r" s", lambda m: w.set("start_time_s", float(next(g for g in m.groups() if g))))


def _lateral_rules(w: _Work) -> None:
    def reverse(m: re.Match[str]) -> None:
        w.set("reverse", True)

    w.take(r"(?:shift|shifts|move|moves|nudge|nudges|slide|slides|offset|drift|drifts|steer|steers)(?: it| over|"
           r" sideways)?"
           r" " + _N + r" m (?:to the |towards the |over to the |to its )?(left|right)",
           lambda m: w.set("lateral_offset_m", float(m.group(1)) * (1 if m.group(2) == "left" else -1)))
    w.take(r"reverse|reverses|reversing|back(?:s|ing)? (?:up|out|it up)|back up|(?:drive|drives|go|goes|move|moves|roll"
           r"|rolls|head|heads|travel|travels)(?: it)? backwards?|(?:in|into) reverse(?: gear)?|go back(?:wards)?$",
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
        phrase, end = w.noun_phrase_after(w.text.rfind("|") + 1)
        if phrase:
            w.blank(w.text.index(phrase), end)
    if "lane_change" not in w.out.fields and re.search(_AMBIGUOUS_LANE, w.text):
        w.out.refusal = "a lane change needs a side: say 'change lanes to the left' or 'to the right'"
        w.out.refusal_field = "lane_change"
        w.take(_AMBIGUOUS_LANE)


def _turn_rules(w: _Work) -> None:
    if w.take(r"u[- ]?turn|u[- ]?turns|turn(?:s)? (?:it |them )?(?:around|back)|do a 180|pull a 180"):
        w.out.refusal = "U-turns are not supported (turn left or right, or go straight, at the next intersection)"
        w.out.refusal_field = "turn"
    w.take(r"(?:do not|does not|not|never|no|without) turn(?:ing)?(?: (?:left|right))?"
           r"|(?:go|goes|going|drive|drives|driving|continue"
           r"|continues|continuing|keep|keeps|keep going|keep driving|carry on|carries on|head|heads|proceed|proceeds"
           r"|stay|stays|travel|travels|run)(?: on)? straight(?: on| ahead| through| across)?|"
           r"straight (?:through|across"
           r"|on|ahead)", lambda m: w.set("turn", "straight"))
    w.take(r"(?:turn|turns|turning|hang|hangs|take|takes|make|makes|swing|swings|bear|bears|go|goes|head|heads|hook"
           r"|hooks)(?: off)?(?: a| an| the)?(?: (?:next|first|upcoming))? (?:to the )?(left|right)(?:[- ]hand)?"
           r"(?: turn)?(?! lane)|(left|right)(?:[- ]hand)? turn",
           lambda m: w.set("turn", m.group(1) or m.group(2)))


def _pedestrian_rules(w: _Work) -> None:
    jay = (r"away from (?:the |any )?(?:crosswalk|zebra(?: crossing)?)|mid[- ]?block|not (?:at|on|using|"
           r"via) (?:the |a )?"
           r"(?:crosswalk|zebra(?: crossing)?)|in the middle of the (?:road|street|block)|outside (?:of )?(?:the |a )?"
           r"(?:crosswalk|zebra(?: crossing)?)|illegally|without (?:using )?(?:the |a )?(?:crosswalk|"
           r"zebra(?: crossing)?)"
           r"|where there is no (?:crosswalk|zebra)")
    jaywalking = w.take(r"jaywalk\w*(?: (?:across|over))?(?: (?:the|a) (?:street|road))?") | w.take(jay)
    gaits = {"run": r"run|runs|running|sprint|sprints|sprinting|jog|jogs|jogging|dash|dashes|race|races|rush|rushes"
                    r"|bolt|bolts",
             "walk": r"walk|walks|walking|stroll|strolls|amble|ambles|saunter|saunters|wander|wanders"}
    crossed = w.take(r"(?:(?:cross|crosses|crossing)" + _CROSSABLE + r"|(?:(?:" + gaits["run"] + "|" + gaits["walk"]
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
        w.take(gaits["run"], lambda m: w.set("gait", "run"))
    if "gait" not in w.out.fields:
        w.take(gaits["walk"], lambda m: w.set("gait", "walk"))


def _gait_of(w: _Work, phrase: str, gaits: dict[str, str]) -> None:
    for gait, rx in gaits.items():
        if re.match(r"(?:" + rx + r")\b", phrase):
            w.set("gait", gait)


def _longitudinal_rules(w: _Work) -> None:
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
           r"|increase (?:its |the )?speed",
           lambda m: w.set("longitudinal", "accelerate") if "longitudinal" not in w.out.fields else None)


def _follow_rules(w: _Work) -> None:
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


def _op_rules(w: _Work) -> None:
    if w.take(r"disappear|disappears|vanish|vanishes|go away|goes away|be (?:removed|deleted|gone|erased)|leave the "
              r"(?:scene|road|picture)|get (?:out|off) (?:of )?the (?:scene|road)|cease to exist|be taken out"):
        w.out.op = "remove"


def _neutral_rules(w: _Work) -> None:
    w.take(r"than (?:now|before|it (?:is|was)|it does now|currently|usual|normal|normally|in the log|originally"
           r"|its current speed|the others?|other cars)|towards? (?:us|me|the ego(?: vehicle| car)?)|the other way"
           r"|in the opposite direction|against (?:the )?traffic", repeat=True)
    if w.take(r"go|goes|drive|drives|move|moves|continue|continues|proceed|proceeds|keep going|carry on|keep driving"
              r"|resume|resumes|start moving|get going|go on|drive on|move on|set off|ride|rides|riding|cycling"
              r"|biking|cycle|cycles", repeat=True):
        w.out.neutral = True


def _negation(w: _Work) -> None:
    if re.search(r"(?<![\w-])(?:do not|does not|not|never|no longer|no)(?![\w-])", w.text):
        w.out.refusal = w.out.refusal or "negated edits ('do not ...') are not supported: say what should happen"


def parse_predicate(text: str, kind: str | None = None) -> PredicateParse:
    """Behaviour fields of a canonical predicate (module docstring).

    Args:
        text: canonical predicate words ("slow down to 20 km/h").
        kind: ``"vehicle"`` / ``"pedestrian"`` / ``"static"`` / ``None`` -- only changes "hurry" (a pedestrian
            runs, a vehicle accelerates).
    """
    w = _Work(text, kind)
    _op_rules(w)
    _turn_rules(w)  # before speeds: "do not turn" is not a negated speed
    _speed_rules(w)
    _timing_rules(w)
    _stop_rules(w)
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
