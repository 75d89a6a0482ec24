"""Speed, stop and timing rules of the predicate reader: the ``parse_rule`` of the speed, stop and timing behaviours
(``editing.behaviours``), here as they share the reading of numbers, units and times.

Speeds: absolute ("40 km/h", "at 15 m/s"; a bare number after a speed verb is km/h), factor ("twice as
fast", "half the speed", "three times faster", "50 % faster" -> 1.5) or delta ("10 km/h slower" -> -10,
"speed up by 5 mph"). Stops: at a time ("at 2 s", "after 1.5 seconds"), before a crosswalk, intersection
or stop line ("stop 5 m before the crosswalk"), behind an object; "brake hard" / "slam on the brakes"; a
stationary state ("not moving", "who is not walking": a description, not a negated edit) is a stop.
Timing: a start time ("wait 2 s before moving", "start moving at 4 s") or a delay ("start 3 s later").
"""

from __future__ import annotations

import re

from simsplat_core.editing.commands import SpeedSpec
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse import lexicon as lex
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.editing.parse.text import number_word
from simsplat_core.scenario import vocabulary as voc

_N = r"(\d+(?:\.\d+)?)"
_SPEED = _N + r" (km/h|m/s|mph)"
_STOP_PLACES = (r"(crosswalk|zebra crossing|zebra|pedestrian crossing|crossing|" + voc.INTERSECTION_RX
                + r"|stop line|stop sign|traffic lights?|lights?|red light|signal)")

#: "before *it reaches* the crosswalk", "before *getting to* the junction": the place is the same.
_REACHES = (r"(?:(?:it |they |he |she )?(?:reaches|reach|reaching|gets to|get to|getting to|arrives at|arrive at"
            r"|arriving at|enters|enter|entering|hits|hit|hitting) )?")


def _factor(word: str) -> float | None:
    table = {"twice": 2.0, "double": 2.0, "doubles": 2.0, "triple": 3.0, "triples": 3.0, "thrice": 3.0,
             "quadruple": 4.0, "half": 0.5, "halve": 0.5, "halves": 0.5}
    return table.get(word, number_word(word))


#: Verbs that set a speed ("*reduce* its speed to 8 km/h", "*set* the speed of the bus to 30 km/h").
SPEED_VERB = r"(?:" + "|".join(lex.SPEED_VERBS) + r")"
#: A speed as a noun ("the *walking speed* of the man").
SPEED_NOUN = r"(?:(?:walking|driving|travel|travelling|running|cruising) )?(?:speed|pace)"


def speed_rules(w: PredicateWork) -> None:
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

    def absolute(value: str, unit: str, words: str = "") -> bool:
        w.set("speed", SpeedSpec(mode="absolute", value=float(value), unit=unit))  # type: ignore[arg-type]
        gait = re.search(r"\b(walk|run)s?\b", words)
        if gait:
            w.set("gait", gait.group(1))
        return True

    w.take(SPEED_VERB + r"(?:s)? (?:its |the |their )?" + SPEED_NOUN + r"(?: down| up)? to " + _SPEED,
           lambda m: absolute(m.group(1), m.group(2)))  # "reduce its speed to 8 km/h"
    w.take(_SPEED + r" " + faster, lambda m: delta(m, 1.0))
    w.take(_SPEED + r" " + slower, lambda m: delta(m, -1.0))
    w.take(up + r"(?: by)? " + _SPEED, lambda m: delta(m, 1.0))
    w.take(down + r"(?: by)? " + _SPEED, lambda m: delta(m, -1.0))
    w.take(r"(?:faster|quicker) by " + _SPEED, lambda m: delta(m, 1.0))
    w.take(r"slower by " + _SPEED, lambda m: delta(m, -1.0))

    lead = (r"(?:(?:at|to|with|of|reach|reaches|hit|hits|doing|do|does|maintain|maintains|keep|hold|a|an|constant"
            r"|steady|top|speed|up|down|limit|exactly|only|just|the|going|go|goes|drive|drives|travel|travels|cruise"
            r"|move|moves|walk|walks|run|runs) )*")
    w.take(lead + _SPEED, lambda m: absolute(m.group(1), m.group(2), m.group(0)))
    w.take(r"(?:(?:go|goes|drive|drives|travel|travels|cruise|cruises|move|moves|speed up|accelerate|accelerates"
           r"|slow down|slow|slows down|decelerate|decelerates|brake|brakes)(?: down| up)? (?:at|to) |(?:a )?speed of )"
           + _N + r"(?! (?:m|s|%|deg)\b)", lambda m: absolute(m.group(1), "km/h"))


def stop_rules(w: PredicateWork) -> None:
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
        r"|(?:stop (?:moving|walking|running|driving)|stop|stops|stopping|halt|halts|pull over|pulls over|pull up"
        r"|pulls up|park|parks|freeze|freezes|stand still|stay still|stays still|stay put|keep still|remain still"
        r"|(?:be |is |are )?standing still|be (?:stationary|stopped|at (?:a )?(?:standstill|rest))"
        r"|remain stationary|stay stationary|cease moving|yield|yields|give way|gives way|wait|waits"
        r"|(?:not|no longer) (?:moving|walking|driving|going anywhere|in motion))(?! sign| line)",
        lambda m: w.stop(), repeat=True) or "stop" in w.out.fields
    if not stopped:
        return
    w.take(r"(?:at|after|in|within|by|around) " + _N + r" s|" + _N + r" s (?:later|from now|into the \w+)",
           lambda m: w.stop(at_time_s=float(m.group(1) or m.group(2))))

    def before(m: re.Match[str]) -> None:
        place = m.group(2)
        kind = ("intersection" if place in voc.INTERSECTION_NOUNS
                else "crosswalk" if re.match(r"cross|zebra|pedestrian", place) else "stop_line")
        w.stop(before=kind, **({"gap_m": float(m.group(1))} if m.group(1) else {}))

    w.take(r"(?:" + _N + r" m )?(?:right |just |directly )?(?:before|at|short of|in front of|ahead of|prior to|by"
           r"|near|for|behind|ahead)? ?" + _REACHES + r"(?:the |a )?(?:next |upcoming |first |nearest |coming )?"
           + _STOP_PLACES, before)
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


def timing_rules(w: PredicateWork) -> None:
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
