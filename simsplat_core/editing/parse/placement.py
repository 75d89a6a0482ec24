"""Where to put something, and what to put: canonical words -> placement parts and an ``AssetSpec``.

    find_placement("2 m to the left of the white van".split(), positions=())
    # PlacementParse(relation="left_of", anchor="the white van", distance_m=2.0, ...)

Placements: relative to an anchor noun phrase ("in front of the construction worker", "3 m right of the
black sedan", "next to the parked truck"; no noun phrase or "us" = the ego), in a lane ("in the ego lane
20 m ahead", "in the left lane", "in the oncoming lane"), on a map area ("on the crosswalk", "on the
sidewalk", "on the road"; "by the curb" is on the road) or absolute ("at (10, -3, 0)", "at x=12 y=3"),
with an optional frame ("at frame 10") and heading ("facing left", "rotated 90 degrees"). A lane phrase
makes an ``in_lane`` placement whose distance and anchor come from "N m ahead (of X)"; a map area keeps
the anchor and distance it is given with.

Assets: the grounding parser (``grounding.parse.parse_query``) reads category, subtype and colours of the
noun phrase; counts come from numbers, number words, "a row of" and bare plurals.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from simsplat_core.editing.commands import AssetSpec
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse import lexicon as lex
from simsplat_core.editing.parse.anchor import qualifier_length
from simsplat_core.editing.parse.text import number_word
from simsplat_core.language.grounding.parse import NOUNS, parse_query
from simsplat_core.scenario import vocabulary as voc

_N = r"(\d+(?:\.\d+)?)"
_D = r"(?:(?P<d>\d+(?:\.\d+)?) m )?"
_EGO = r"(?:us|me|ego|the ego(?: vehicle| car)?|our (?:car|vehicle)|my (?:car|vehicle))"
#: ``(regex up to the anchor noun phrase, relation)``; group 1 is the distance, a ``side`` group left/right.
_RELATIVE: tuple[tuple[str, str], ...] = (
    (_D + r"(?:to the |on the |at the |off to the )?(?P<side>left|right)(?:[- ]hand)?(?: side)? of", "side"),
    (_D + r"(?:right |directly |just |straight )?(?:in front of|ahead of|before)", "in_front_of"),
    (_D + r"(?:right |directly |just )?(?:behind|in back of|at the back of|to the rear of|after)", "behind"),
    (_D + r"(?:right |directly |just )?(?:next to|beside|alongside|near|close to|by the side of|nearby|adjacent to"
     r"|close by|right by|by)", "next_to"),
)
#: Relations to the ego without a noun phrase ("20 m ahead", "on our left").
_EGO_RELATIVE: tuple[tuple[str, str], ...] = (
    # "away from the crosswalk" says where not to be, not how far ahead
    (_D + r"(?:up )?(?:ahead|in front|forward|down the road|up the road|further(?: ahead| up| down)?|away)"
          r"(?! of| from)", "in_front_of"),
    (r"(?P<d>\d+(?:\.\d+)?) m (?:behind|back)(?! of)", "behind"),
    (r"(?:to|on|at) (?:the|our|my) (?P<side>left|right)(?:[- ]hand)?(?: side)?(?! of| lane)", "side"),
)
_LANES: tuple[tuple[str, str], ...] = (
    (r"(?:in|along|down|into) (?:the |our |my )?(?P<side>left|right)(?:[- ]hand)?(?:[- ]?most)? lane"
     r"|in the lane (?:to|on) (?:the |our |my )?"
     r"(?P<side2>left|right)|(?:one|1) lane (?:to the |over to the |over on the )?(?P<side3>left|right)|in the (?:next"
     r"|adjacent|neighbouring|neighboring) lane (?:to|on) the (?P<side4>left|right)", "side"),
    (r"in (?:the )?(?:oncoming|opposite|opposing|other|contraflow) (?:lane|direction|traffic)|in oncoming traffic"
     r"|on the other side of the road|in the lane going the other way"
     r"|in the lane (?:of|for|with) (?:the )?(?:oncoming|opposing) traffic", "opposite"),
    (r"in (?:the |our |my |its )?(?:ego|own|same|current)(?: vehicle| car)?(?:'s)? lane(?: as)?"
     r"|in (?:our|my|its) lane|in the lane of the ego(?: vehicle| car)?"
     r"|in the (?:same )?lane (?:that )?(?:we are|i am) in|in (?:the |this )?lane(?= |$)"
     r"|(?<![a-z] )(?:the )?(?:same|our|my) lane(?! as)", "same"),  # ", same lane" / "10 m ahead, our lane"
)
_AREAS: tuple[tuple[str, str], ...] = (
    (r"(?:on|onto|at|in|over|in the middle of) (?:the |a )?(?:crosswalk|zebra crossing|zebra"
     r"|pedestrian crossing|crossing)", "on_crosswalk"),
    (r"(?:on|onto|along|at|up on|in) (?:the |a )?(?:sidewalk|pavement|footpath|walkway|footway)"
     r"|(?:on|onto|up on) (?:the |a )?(?:curb|kerb)|(?:at|on) the (?:street )?corner", "on_sidewalk"),
    (r"(?:on|at|to|by) the (?:(?:left|right)(?:[- ]hand)? )?side of the (?:road|street|lane)"
     r"|(?:on|onto|in|into|in the middle of|at) (?:the |a )?(?:road|street|roadway|carriageway"
     r"|middle of the road|" + voc.INTERSECTION_RX + r")|(?:by|at|next to|along|near|on) (?:the )?(?:curb|kerb|roadside"
     r"|side of the road|edge of the road|shoulder)", "on_road"),
)


@dataclass
class PlacementParse:
    """Placement parts found in some words (``anchor``: a noun phrase, ``None`` = the ego)."""

    relation: str | None = None
    anchor: str | None = None
    distance_m: float | None = None
    lane: str | None = None
    position: tuple[float, float, float] | None = None
    heading_deg: float | None = None
    frame: int | None = None
    refusal: str | None = None


def _side(m: re.Match[str]) -> str | None:
    for name in ("side", "side2", "side3", "side4"):
        if name in m.re.groupindex and m.group(name):
            return m.group(name)
    return None


class _Scan:
    def __init__(self, tokens: Sequence[str], mover: str | None) -> None:
        self.text = " " + " ".join(tokens) + " "
        self.mover = mover

    def find(self, rx: str) -> re.Match[str] | None:
        for m in re.finditer(r"(?<![\w/-])(?:" + rx + r")(?![\w/-])", self.text):
            if "|" not in m.group(0):
                return m
        return None

    def blank(self, start: int, end: int) -> None:
        self.text = self.text[:start] + " " + "|" * max(end - start - 2, 1) + " " + self.text[end:]

    def anchor_after(self, end: int) -> tuple[str, int]:
        """The anchor noun phrase after character ``end`` with the words that describe it
        (``editing.parse.anchor``), and its end; ``("", end)``: none."""
        phrase, _, stop = chunks.np_after(self.text, end, _ANCHOR_EXCLUDE, mode="anchor")
        if not phrase or chunks.is_quantity(phrase.split(), 0):
            return "", end
        if re.fullmatch(_EGO, phrase):
            return phrase, stop
        after = chunks.words_from(self.text, stop)
        k = qualifier_length([m.group(0) for m in after], anchor=phrase, mover=self.mover)
        if k:
            phrase, stop = self.text[end:stop + after[k - 1].end()].strip(), stop + after[k - 1].end()
        return phrase, stop

    def residual(self) -> list[str]:
        return [t for t in self.text.split() if "|" not in t]


#: What ends an anchor's head noun phrase (besides participles and relative clauses): another placement's
#: words; ``editing.parse.anchor`` then reads which of the words after it still describe the anchor.
_ANCHOR_EXCLUDE = ("at", "in front of", "behind", "next to", "ahead of", "in", "on", "to the left of",
                   "to the right of", "left of", "right of", "before", "after", "by", "beside")


def find_placement(tokens: Sequence[str], positions: Sequence[tuple[float, float, float]],  # noqa: C901, PLR0915 -- placement grammar: one branch per phrase form, in precedence order
                   mover: str | None = None) -> tuple[PlacementParse | None, list[str]]:
    """The placement in ``tokens`` (canonical words after the asset or target) and the words it did not use.

    Args:
        mover: agent kind of what is placed ("vehicle" / "pedestrian" / "static"; None: unknown), which decides
            whose a motion phrase after the anchor is (``editing.parse.anchor``).
    """
    s = _Scan(tokens, mover)
    out = PlacementParse()
    found = False
    m = s.find(r"between")
    if m:
        out.refusal = "placing something 'between' two objects is not supported: use next to, in front of or behind one"
        return out, []
    m = s.find(r"(?:(?:at|to|on) )?(?:the )?(?:position|location|coordinates|point|spot )?@pos(\d+)")
    if m:
        out.position = positions[int(m.group(1))]
        s.blank(m.start(), m.end())
        found = True
    m = s.find(r"(?:at|in|from|on|for) frame (\d+)|frame (\d+)")
    if m:
        out.frame = int(m.group(1) or m.group(2))
        s.blank(m.start(), m.end())
        found = True
    m = s.find(r"(?:facing|heading|pointing|rotated|turned|oriented|angled|yawed)(?: at| by)? (-?\d+(?:\.\d+)?) deg"
               r"|(?:at an angle of|with a heading of|heading of|yaw of|yaw) (-?\d+(?:\.\d+)?) deg")
    if m:
        out.heading_deg = float(m.group(1) or m.group(2))
        s.blank(m.start(), m.end())
    else:
        for rx, deg in ((r"facing (?:backwards?|the other way|the opposite (?:way|direction)|the wrong way|us"
                         r"|towards? us|the camera|oncoming traffic)|the wrong way", 180.0),
                        (r"facing (?:to the )?left", 90.0), (r"facing (?:to the )?right", -90.0),
                        (r"(?:facing )?sideways", 90.0),
                        (r"facing (?:forwards?|ahead|the same way|the same direction)", 0.0)):
            m = s.find(rx)
            if m:
                out.heading_deg = deg
                s.blank(m.start(), m.end())
                break
    relative, distance, anchor, anchor_end = _anchor_relative(s)
    for rx, lane in _LANES:
        m = s.find(rx)
        if (m and anchor is not None and relative != "in_front_of" and m.start() >= anchor_end
                and "|" not in s.text[anchor_end : m.start()]):
            anchor += " " + s.text[anchor_end : m.end()].strip()  # "behind the suv in the oncoming lane": its lane
            s.blank(anchor_end, m.end())
            break
        if m:
            out.lane = lane if lane != "side" else _side(m)
            s.blank(m.start(), m.end())
            if m.group(0).endswith(" as"):
                out.anchor, end = s.anchor_after(m.end())
                s.blank(m.start(), end)
            found = True
            break
    for rx, area in _AREAS:
        m = s.find(rx)
        if m:
            out.relation = area
            s.blank(m.start(), m.end())
            found = True
            break
    if relative is None and distance is None:
        relative, distance = _ego_relative(s)
    found = found or relative is not None
    if relative is not None or distance is not None:
        out.distance_m = distance
        out.anchor = anchor if anchor is not None else out.anchor
    if out.position is not None:
        out.relation = "absolute"
    elif out.lane is not None and relative in (None, "in_front_of"):
        out.relation = "in_lane"
    elif out.lane is not None:
        out.refusal = (f"a lane placement is measured ahead of its anchor ('in the left lane 20 m ahead'); "
                       f"{str(relative).replace('_', ' ')} in a given lane is not supported")
    elif out.relation is None:
        out.relation = relative
    return (out if found else None), s.residual()


def _distance(m: re.Match[str]) -> float | None:
    return float(m.group("d")) if "d" in m.re.groupindex and m.group("d") else None


def _anchor_relative(s: _Scan) -> tuple[str | None, float | None, str | None, int]:
    """``(relation, distance, anchor phrase, its end)`` of a placement relative to a noun phrase (``anchor``
    None: the ego), read before lanes and areas so that an anchor keeps its own ("the van parked at the curb")."""
    matches = sorted(((m, relation) for rx, relation in _RELATIVE
                      for m in re.finditer(r"(?<![\w/-])(?:" + rx + r")(?= )", s.text)), key=lambda c: c[0].start())
    for m, relation in matches:  # the first in the text: "beside the van to the right of us" is beside the van
        if "|" in m.group(0):
            continue
        phrase, end = s.anchor_after(m.end())
        ego = re.fullmatch(_EGO, phrase) is not None
        words = phrase.split()
        if not phrase or not ego and words[chunks.chunk_np(words, 0, "inner") - 1] in lex.PLACE_NOUNS:
            continue  # "on the right side of the road" is an area
        s.blank(m.start(), end)
        rel = relation if relation != "side" else f"{_side(m)}_of"
        return rel, _distance(m), None if ego else phrase, end
    return None, None, None, -1


def _ego_relative(s: _Scan) -> tuple[str | None, float | None]:
    """``(relation, distance)`` of a placement relative to the ego without a noun phrase ("20 m ahead")."""
    for rx, relation in _EGO_RELATIVE:
        found = s.find(rx)
        if found:
            s.blank(found.start(), found.end())
            rel = relation if relation != "side" else f"{_side(found)}_of"
            return rel, _distance(found)
    found = s.find(_N + r" m")
    if found:
        s.blank(found.start(), found.end())
        return None, float(found.group(1))
    return None, None


# --------------------------------------------------------------------------------------------------- assets


@dataclass(frozen=True)
class AssetParse:
    """An asset noun phrase read: the spec, or why it cannot be inserted."""

    spec: AssetSpec | None
    refusal: str | None = None


def _count(tokens: Sequence[str]) -> tuple[int | None, int]:
    """``(count given by the leading words or None, tokens they take)``."""
    k = chunks.match(tokens, 0, lex.QUANTITY_PHRASES)
    if k:
        given = number_word(tokens[k]) if k < len(tokens) else None  # "a line of *3* cones"
        if given is not None and given == int(given) and given > 0:
            return int(given), k + 1
        return lex.QUANTITY_PHRASES[" ".join(tokens[:k])], k
    if tokens and tokens[0] in ("a", "an", "another", "one", "1", "single", "a single", "one more"):
        return 1, 1
    if tokens:
        value = number_word(tokens[0])
        if value is not None and value == int(value):
            return int(value), 1
    return None, 0


def parse_asset(tokens: Sequence[str], rest: Sequence[str] = ()) -> AssetParse:
    """The :class:`AssetSpec` of an asset noun phrase ("a row of orange cones", "a pedestrian in a red coat").

    Args:
        tokens: the noun phrase's canonical words.
        rest: the words after it (read for a spacing: "2 m apart", "every 3 m").
    """
    phrase = " ".join(tokens)
    count, k = _count(tokens)
    body = " ".join(tokens[k:]) or phrase
    category = subtype = None
    for n in range(lex.HEAD_NOUN_MAX_WORDS, 0, -1):
        words = [" ".join(tokens[i : i + n]) for i in range(len(tokens) - n + 1)]
        hit = next((w for w in words if w in lex.EXTRA_ASSET_NOUNS), None)
        if hit:
            category, subtype = lex.EXTRA_ASSET_NOUNS[hit]
            break
    query = parse_query(body)
    if query.categories:
        category = lex.ASSET_CATEGORY[query.categories[0]] if category is None else category
        subtype = subtype or query.subtype
        if query.categories == ("cyclist",):
            subtype = subtype or "bicycle"
    if category is None:
        return AssetParse(None, f"I do not know how to insert {phrase!r}: the asset bank holds vehicles (car, taxi, "
                                "SUV, van, pickup truck, truck, bus, motorcycle), pedestrians (adult, child, "
                                "worker) and static objects (traffic cone, barrier, barrel, sign)")
    plural = query.group or any(tokens[i] in _PLURALS for i in range(len(tokens)))
    if count is None:
        count = lex.PLURAL_COUNT if plural else 1
    colour = (query.colors[0] if query.colors else query.upper_color or query.lower_color)
    spacing = _SPACING_RX.search(" ".join(rest))
    spacing_m = float(next(g for g in spacing.groups() if g)) if spacing else None
    if count > 20:
        return AssetParse(None, f"{phrase!r} asks for {count} objects; at most 20 can be inserted at once")
    return AssetParse(AssetSpec(description=phrase, category=category, subtype=subtype,  # type: ignore[arg-type]
                                color=colour, count=count, spacing_m=spacing_m))


_PLURALS = frozenset(w for w, (_, plural) in NOUNS.items() if plural) | frozenset(
    w for w in lex.EXTRA_ASSET_NOUNS if w.endswith("s"))
_SPACING_RX = re.compile(r"(?:^| )(?:" + _N + r" m (?:apart|spacing|between (?:them|each))|spaced(?: out)?(?: by)? "
                         + _N + r" m(?: apart)?|every " + _N + r" m|(?:a )?spacing of " + _N + r" m)")


def spacing_words(tokens: Sequence[str]) -> list[str]:
    """``tokens`` without a row's spacing phrase (read by :func:`parse_asset`)."""
    return _SPACING_RX.sub(" ", " ".join(tokens)).split()
