"""Prompt text made regular for the edit parser: case, contractions, number words, units and coordinates.

    canonical("Pls put two cones 2.5 metres left of the van & make it go 20kph").text
    # "put two cones 2.5 m left of the van and make it go 20 km/h"

* lower case, straight quotes, contractions expanded ("don't" -> "do not", "let's" -> "let us");
* number words are turned into digits only before a unit ("two metres" -> "2 m", "twenty-five km/h" ->
  "25 km/h", "one and a half seconds" -> "1.5 s"); elsewhere they stay words, so descriptions such as
  "the two pedestrians" reach the grounding parser as written (``number_word`` reads counts);
* units: speeds ``km/h`` (kph, kmh, kilometres per hour ...), ``m/s``, ``mph``; distances ``m`` (metres,
  meters, feet -> m); times ``s`` (sec, seconds, minutes -> s); ``%``; ``deg``;
* coordinates "(10, -3, 0)", "x=12 y=3" become ``@pos<i>`` tokens (values in :attr:`Canonical.positions`);
  "t=2" becomes "at 2 s";
* "left hand" / "right hand" are written "left-hand" / "right-hand" ("on the right hand side");
* clause punctuation (``, ; . ! ? :``) becomes separate tokens; other punctuation goes.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

#: Cardinal number words (units and tens; compounds such as "twenty five" are summed).
_UNITS_WORDS: dict[str, float] = {
    "zero": 0, "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9,
    "ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14, "fifteen": 15, "sixteen": 16,
    "seventeen": 17, "eighteen": 18, "nineteen": 19, "a dozen": 12, "dozen": 12,
}
_TENS_WORDS: dict[str, float] = {
    "twenty": 20, "thirty": 30, "forty": 40, "fifty": 50, "sixty": 60, "seventy": 70, "eighty": 80, "ninety": 90,
}
#: Count words that are not numbers ("a row of cones": see ``editing.parse.lexicon.ROW_COUNT``).
_VAGUE_COUNTS: dict[str, int] = {"a couple of": 2, "a pair of": 2, "a few": 3, "several": 4, "some": 3}

_CONTRACTIONS: tuple[tuple[str, str], ...] = (
    (r"\bcan't\b|\bcannot\b", "can not"), (r"\bwon't\b", "will not"), (r"\blet's\b", "let us"),
    (r"\b(\w+)n't\b", r"\1 not"), (r"\b(i|you|we|they)'d\b", r"\1 would"), (r"\b(i|you|we|they)'ll\b", r"\1 will"),
    (r"\b(it|that|there|he|she|what|where|who|which)'s\b", r"\1 is"), (r"\b(\w+)'re\b", r"\1 are"),
    (r"\bi'm\b", "i am"),
    (r"\b(i|you|we|they)'ve\b", r"\1 have"), (r"\bgonna\b", "going to"), (r"\bwanna\b", "want to"),
    (r"\bgotta\b", "has to"),
)
_FILLER_RX = re.compile(r"(?<![\w-])(?:please|pls|plz|kindly|thanks|thank you|thx|ty)(?![\w-])")

_NUM = r"-?(?:\d+(?:\.\d+)?|\.\d+)"
_UNIT_TABLE: tuple[tuple[str, str, float], ...] = (
    # (regex of the unit after a number, canonical unit, factor to the canonical unit)
    (r"km ?/ ?h(?:r|our)?|kmh|kph|kmph|km ?p ?h|k(?:ilo)?m(?:et(?:er|re)s?)? (?:per|an|a|/) ?h(?:ou)?r|"
     r"kilomet(?:er|re)s? (?:per|an|a) hour|kilomet(?:er|re)s? ?/ ?h(?:our)?|kms? (?:per|an|a) hour|"
     r"km/hour", "km/h", 1.0),
    (r"m ?/ ?s(?:ec)?|mps|met(?:er|re)s? (?:per|a|/) ?sec(?:ond)?|met(?:er|re)s? ?/ ?s(?:ec(?:ond)?)?|"
     r"m per s(?:ec(?:ond)?)?", "m/s", 1.0),
    (r"mph|mi ?/ ?h|miles? (?:per|an|a) hour|miles? ?/ ?h(?:ou)?r", "mph", 1.0),
    (r"met(?:er|re)s?|mtrs?|m", "m", 1.0),
    (r"feet|foot|ft", "m", 0.3048),
    (r"yards?|yds?", "m", 0.9144),
    (r"seconds?|secs?|s", "s", 1.0),
    (r"minutes?|mins?", "s", 60.0),
    (r"%|percent|per cent|pct", "%", 1.0),
    (r"degrees?|degs?|°", "deg", 1.0),
)
_UNIT_RX = re.compile(
    r"(?<![\w.])(" + _NUM + r") ?(" + "|".join(f"(?:{rx})" for rx, _, _ in _UNIT_TABLE) + r")(?![\w/])"
)
_UNIT_PARTS = tuple((re.compile(r"(?:" + rx + r")\Z"), unit, factor) for rx, unit, factor in _UNIT_TABLE)

_COORD_RX = re.compile(r"\(\s*(" + _NUM + r")\s*,\s*(" + _NUM + r")\s*(?:,\s*(" + _NUM + r")\s*)?\)")
_XYZ_RX = re.compile(
    r"\bx\s*=\s*(" + _NUM + r")\s*,?\s*(?:and\s+)?y\s*=\s*(" + _NUM + r")"
    r"(?:\s*,?\s*(?:and\s+)?z\s*=\s*(" + _NUM + r"))?"
)
_TIME_EQ_RX = re.compile(r"\b(?:at )?t ?= ?(" + _NUM + r") ?(?:s|secs?|seconds?)?(?![\w.])")
_APPROX_RX = re.compile(r"(?<![\w-])(?:about|around|roughly|approximately|approx\.?|~|circa|some|like)\s+(?=-?\.?\d)")


@dataclass(frozen=True)
class Canonical:
    """A prompt in canonical form.

    Attributes:
        text: canonical text (module docstring); tokens are separated by single spaces.
        positions: the ``@pos<i>`` coordinates, ``(x, y, z)`` metres (``z`` 0 when not given).
    """

    text: str
    positions: tuple[tuple[float, float, float], ...] = ()

    @property
    def tokens(self) -> list[str]:
        return self.text.split()


def _number_phrase(words: str) -> float | None:
    """The value of a number phrase in words or digits ("twenty five", "one and a half", "2.5"), else None."""
    words = words.strip().replace("-", " ")
    if re.fullmatch(_NUM, words):
        return float(words)
    half = 0.0
    if words.endswith(" and a half"):
        words, half = words[: -len(" and a half")], 0.5
    if words in ("half a", "half an", "a half"):
        return 0.5
    if words in ("a", "an"):
        return 1.0 + half
    total = 0.0
    parts = words.split()
    if not parts:
        return None
    i = 0
    if parts[0] in _TENS_WORDS:
        total += _TENS_WORDS[parts[0]]
        i = 1
    rest = " ".join(parts[i:])
    if rest:
        if rest not in _UNITS_WORDS or (i and _UNITS_WORDS[rest] >= 10):
            return None
        total += _UNITS_WORDS[rest]
    return total + half


_WORD_NUM = (r"(?:(?:" + "|".join(_TENS_WORDS) + r")(?:[ -](?:one|two|three|four|five|six|seven|eight|nine))?|"
             + "|".join(sorted(_UNITS_WORDS, key=len, reverse=True))
             + r")(?: and a half)?|half an?|an?(?= (?:sec|min))")
_WORD_NUM_RX = re.compile(r"(?<![\w-])(" + _WORD_NUM + r") (?=(?:" + "|".join(rx for rx, _, _ in _UNIT_TABLE)
                          + r")(?![\w/]))")


def number_word(word: str) -> float | None:
    """A count or number written as digits or a word ("3", "three", "a dozen"), else None."""
    return _number_phrase(word) if word not in ("a", "an") else None


def vague_count(phrase: str) -> int | None:
    """Counts of vague quantity words ("a few" -> 3, "a couple of" -> 2), else None."""
    return _VAGUE_COUNTS.get(phrase)


def _fmt(value: float) -> str:
    return f"{value:g}"


def _unit_sub(m: re.Match[str]) -> str:
    value, unit_text = float(m.group(1)), m.group(2)
    for rx, unit, factor in _UNIT_PARTS:
        if rx.match(unit_text):
            return f" {_fmt(round(value * factor, 3))} {unit} "
    return m.group(0)  # pragma: no cover - every alternative of _UNIT_RX is in _UNIT_PARTS


def canonical(text: str) -> Canonical:
    """The canonical form of a prompt (module docstring). Never raises; empty text gives empty text."""
    t = text.lower().replace("\u2019", "'").replace("\u2018", "'").replace("\u201c", '"').replace("\u201d", '"')
    t = t.replace("&", " and ").replace("w/", "with ").replace("°", " degrees")
    for rx, repl in _CONTRACTIONS:
        t = re.sub(rx, repl, t)
    t = _FILLER_RX.sub(" ", t)
    positions: list[tuple[float, float, float]] = []

    def _pos(m: re.Match[str]) -> str:
        x, y, z = (float(g) if g is not None else 0.0 for g in m.groups())
        positions.append((x, y, z))
        return f" @pos{len(positions) - 1} "

    t = _COORD_RX.sub(_pos, t)
    t = _XYZ_RX.sub(_pos, t)
    t = _TIME_EQ_RX.sub(lambda m: f" at {m.group(1)} s ", t)
    t = _APPROX_RX.sub("", t)
    t = re.sub(r"(\d),(\d{3})\b", r"\1\2", t)  # 1,000
    t = _WORD_NUM_RX.sub(lambda m: f"{_fmt(v)} " if (v := _number_phrase(m.group(1))) is not None else m.group(0), t)
    t = re.sub(r"(?<![\w.])(\d+(?:\.\d+)?)(?=[a-z%])", r"\1 ", t)  # "20km/h" -> "20 km/h"
    t = _UNIT_RX.sub(_unit_sub, t)
    t = re.sub(r"(?<=\d)\s*%", " %", t)
    t = re.sub(r"#\s*(\d)", r"\1", t)  # "node #12"
    t = re.sub(r"\b(left|right) hand\b", r"\1-hand", t)  # "the left hand side": one word, as "left-hand"
    # clause punctuation becomes tokens (a decimal point stays inside its number)
    t = re.sub(r"(?<!\d)\.|\.(?!\d)", " . ", t)
    t = re.sub(r"([,;!?:])", r" \1 ", t)
    t = re.sub(r"[^\w\s.,;!?:%/@'-]", " ", t)
    t = re.sub(r"(?<![\w])['-]+|['-]+(?![\w])", " ", t)
    t = re.sub(r"\s+", " ", t).strip()
    return Canonical(t, tuple(positions))
