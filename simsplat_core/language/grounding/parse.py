"""Free-form grounding queries split into their appearance, motion and location parts.

    q = parse_query("find me the pedestrian in a red shirt and blue pants crossing from left to right")
    q.category, q.upper_color, q.lower_color     # "pedestrian", "red", "blue"
    q.motion, q.crossing_direction                # "crossing from left to right", "left_to_right"
    q.appearance                                  # "pedestrian in a red shirt and blue pants"

SIMSplat grounds a description by comparing its appearance with the nodes' appearance features and
its motion and location with the motion and location features (Sec. 3.2). Embedding the whole
sentence mixes the three (E5 scores "the black car turning left at the intersection" closer to
"stopping" than to "turning left" once the other words are in), so the query engine embeds each part
separately, and it needs the parts that the text space cannot tell apart as explicit values: E5
gives "crossing from left to right" and "... right to left" a cosine of 0.997, and "a red shirt and
blue pants" and "a blue shirt and red pants" 0.998.

The parser is rule-based and works on lower-cased text:

1. **Spans.** Regular expressions find motion phrases ("turning left", "making a left turn",
   "crossing from left to right", "parked", "backing up", ...), crossing directions ("from left to
   right", "over to the right side"), ego-relative sectors ("on the right", "ahead of us", "behind
   me", "in the left lane") and map contexts ("at the intersection", "on the crosswalk", "by the
   curb", "oncoming", ...). Overlapping matches are resolved by priority (directional motion, then
   location, then other motion), then by length: "turning left" is motion, "on the left" location,
   and "on the pedestrian crossing" a place, not a crossing pedestrian.
2. **Subject.** Outside the spans, a category noun (``NOUNS``: car, SUV, van, truck, bus, sedan, ...
   -> vehicle with that subtype; pedestrian, person, man, kid, ... -> pedestrian; cyclist, bike;
   cone, barrier; sign, stop sign, ...) gives the allowed node categories and subtype; a plural
   noun, "all", "every", "each", "both" or "the two" make a group query.
3. **Colours** use the captioner's names (``appearance.colors.COLOR_NAMES``; synonyms such as grey,
   navy, maroon, tan map onto them). A colour followed by a garment word is an upper ("shirt",
   "jacket", "top", ...) or lower ("pants", "jeans", "skirt", ...) garment colour; other colours are
   kept unordered (a vehicle's body colour, or "dressed in red").
4. **Negated colours** ("the car that is not red", "a non-white van", "a pedestrian not wearing
   red", "any SUV other than the black one") become ``excluded_colors`` and leave the text: a node whose
   caption has such a colour is contradicted, and "not red" is not embedded (E5 puts "a car that is not
   red" next to "a red car").
5. What remains, less filler words ("find me", "which", "is", ...), is the appearance text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from simsplat_core.color_names import COLOR_NAMES
from simsplat_core.language.grounding.lexicon import OWNER_WORDS
from simsplat_core.scenario import vocabulary as voc

# ---------------------------------------------------------------------------------------------- lexicons

#: Colour words -> captioner colour names.
COLOR_SYNONYMS: dict[str, str] = {
    **{c: c for c in COLOR_NAMES},
    "grey": "gray",
    "charcoal": "gray",
    "navy": "blue",
    "teal": "blue",
    "turquoise": "blue",
    "maroon": "red",
    "crimson": "red",
    "burgundy": "red",
    "scarlet": "red",
    "tan": "beige",
    "khaki": "beige",
    "cream": "beige",
    "gold": "yellow",
    "golden": "yellow",
    "violet": "purple",
    "lilac": "purple",
    "magenta": "pink",
    "olive": "green",
    "lime": "green",
}

UPPER_GARMENTS = (
    "shirt", "t-shirt", "tshirt", "tee", "top", "jacket", "coat", "hoodie", "hoody", "sweater", "jumper",
    "blouse", "vest", "sweatshirt", "parka", "cardigan", "polo", "tank top", "dress",
    "shirts", "t-shirts", "tshirts", "tees", "tops", "jackets", "coats", "hoodies", "sweaters", "jumpers",
    "blouses", "vests", "sweatshirts", "parkas", "cardigans", "polos", "tank tops", "dresses",
)
LOWER_GARMENTS = ("pants", "trousers", "jeans", "shorts", "skirt", "skirts", "leggings", "slacks", "chinos", "bottoms")


@dataclass(frozen=True)
class Noun:
    """A category noun: the node categories it allows, the subtype it names (``None``: any) and its singular."""

    categories: tuple[str, ...]
    subtype: str | None
    singular: str


def _nouns() -> dict[str, tuple[Noun, bool]]:
    """``word -> (Noun, is_plural)``."""
    table: list[tuple[tuple[str, ...], tuple[str, ...], str | None]] = [
        # (singular [, plural ...]), categories, subtype
        (("car", "cars"), ("vehicle",), "car"),
        (("auto", "autos"), ("vehicle",), "car"),
        (("automobile", "automobiles"), ("vehicle",), "car"),
        (("taxi", "taxis"), ("vehicle",), "car"),
        (("ride", "rides"), ("vehicle",), "car"),
        (("motor", "motors"), ("vehicle",), "car"),
        (("cab", "cabs"), ("vehicle",), "car"),
        (("vehicle", "vehicles"), ("vehicle",), None),
        (("sedan", "sedans"), ("vehicle",), "sedan"),
        (("saloon car", "saloon cars"), ("vehicle",), "sedan"),
        (("saloon", "saloons"), ("vehicle",), "sedan"),
        (("hatchback", "hatchbacks"), ("vehicle",), "hatchback"),
        (("sport utility vehicle", "sport utility vehicles"), ("vehicle",), "SUV"),
        (("suv", "suvs"), ("vehicle",), "SUV"),
        (("jeep", "jeeps"), ("vehicle",), "SUV"),
        (("crossover", "crossovers"), ("vehicle",), "SUV"),
        (("van", "vans"), ("vehicle",), "van"),
        (("minivan", "minivans"), ("vehicle",), "van"),
        (("pickup truck", "pickup trucks"), ("vehicle",), "pickup truck"),
        (("pick-up truck", "pick-up trucks"), ("vehicle",), "pickup truck"),
        (("pickup", "pickups"), ("vehicle",), "pickup truck"),
        (("pick-up", "pick-ups"), ("vehicle",), "pickup truck"),
        (("truck", "trucks"), ("vehicle",), "truck"),
        (("lorry", "lorries"), ("vehicle",), "truck"),
        (("bus", "buses", "busses"), ("vehicle",), "bus"),
        (("coach", "coaches"), ("vehicle",), "bus"),
        (("motorcycle", "motorcycles"), ("vehicle", "cyclist"), "motorcycle"),
        (("motorbike", "motorbikes"), ("vehicle", "cyclist"), "motorcycle"),
        (("scooter", "scooters"), ("vehicle", "cyclist"), "motorcycle"),
        (("pedestrian", "pedestrians"), ("pedestrian",), None),
        (("person", "people", "persons"), ("pedestrian",), None),
        (("man", "men"), ("pedestrian",), None),
        (("woman", "women"), ("pedestrian",), None),
        (("guy", "guys"), ("pedestrian",), None),
        (("lady", "ladies"), ("pedestrian",), None),
        (("walker", "walkers"), ("pedestrian",), None),
        (("passer-by", "passers-by"), ("pedestrian",), None),
        (("passerby", "passersby"), ("pedestrian",), None),
        (("individual", "individuals"), ("pedestrian",), None),
        (("jogger", "joggers"), ("pedestrian",), None),
        (("adult", "adults"), ("pedestrian",), "adult"),
        (("someone",), ("pedestrian",), None),
        (("somebody",), ("pedestrian",), None),
        (("child", "children"), ("pedestrian",), "child"),
        (("kid", "kids"), ("pedestrian",), "child"),
        (("boy", "boys"), ("pedestrian",), None),
        (("girl", "girls"), ("pedestrian",), None),
        (("cyclist", "cyclists"), ("cyclist",), None),
        (("bicyclist", "bicyclists"), ("cyclist",), None),
        (("biker", "bikers"), ("cyclist",), None),
        (("bike", "bikes"), ("cyclist",), None),
        (("bicycle", "bicycles"), ("cyclist",), "bicycle"),
        (("traffic cone", "traffic cones"), ("static",), "traffic cone"),
        (("cone", "cones"), ("static",), "traffic cone"),
        (("pylon", "pylons"), ("static",), "traffic cone"),
        (("barrier", "barriers"), ("static",), "barrier"),
        (("barricade", "barricades"), ("static",), "barrier"),
        (("pole", "poles"), ("static",), "pole"),
        (("bollard", "bollards"), ("static",), "pole"),
        (("stop sign", "stop signs"), ("sign",), "stop sign"),
        (("speed limit sign", "speed limit signs"), ("sign",), "speed limit sign"),
        (("speed sign", "speed signs"), ("sign",), "speed limit sign"),
        (("parking sign", "parking signs"), ("sign",), "parking sign"),
        (("road sign", "road signs"), ("sign",), None),
        (("traffic sign", "traffic signs"), ("sign",), None),
        (("street sign", "street signs"), ("sign",), None),
        (("sign", "signs"), ("sign",), None),
    ]
    out: dict[str, tuple[Noun, bool]] = {}
    for words, categories, subtype in table:
        noun = Noun(categories, subtype, words[0])
        for i, word in enumerate(words):
            out[word] = (noun, i > 0 and word not in ("someone", "somebody"))
    for words, _categories, _subtype in table:
        # the plural users type by the regular rule even where English spells it otherwise ("lorrys",
        # "childs", "passer-bys"); a table plural or another noun of that spelling wins
        singular = words[0]
        if len(words) > 1 and not singular.endswith("s"):
            out.setdefault(singular + "s", (out[singular][0], True))
    return out


NOUNS: dict[str, tuple[Noun, bool]] = _nouns()

#: Words that make a query a group query.
GROUP_WORDS = ("all", "every", "each", "both", "the two", "all the", "all of the")

#: Words dropped from the appearance text (request phrasing, articles, copulas, relative pronouns).
FILLERS = frozenset(
    "find me show highlight locate select segment mark point pointing out give please can could you would "
    "mind i i'm want to see spot do look looking for where which what is are was the a an one ones that who "
    "whose there any of all every each both two those these this it its there's that's who's which's what's "
    "where's here it's yo just mean over something anything thing things object objects".split()
)

#: Words that link appearance words without describing anything.
#: Pointing phrases that say nothing about the object ("right there" must not read as "right").
_DEICTIC_RX = re.compile(r"(?<![\w-])(?:right|over|just|out|up|down) (?:there|here)(?![\w-])")

CONNECTIVES = frozenset("and in with wearing dressed a an the or on at to by".split())

# ---------------------------------------------------------------------------------------------- patterns

_SIDE = r"(left|right)"
_DIR = r"(?:the )?(left|right)(?:[- ]hand)?(?: side)?"
_EGO_ALT = r"me|us|ego|the ego(?: vehicle| car)?|our (?:car|vehicle)|my (?:car|vehicle)|the camera"
_EGO = r"(?:" + _EGO_ALT + r")"
_ING_CROSS = (r"(?:crossing|crosses|cross|walking across|walks across|going across|goes across|heading across"
              r"|moving across|running across|jogging across)")
_CROSS_OBJ = r"(?: over)?(?: (?:the|a) (?:street|road|crosswalk|zebra crossing|lane|lanes))?"

#: ``(kind, priority, regex)``; lower priority wins overlaps, then longer matches. Kinds: ``motion``,
#: ``direction`` (a crossing direction, also motion), ``sector``, ``context``. Directional motion comes
#: first (its "left" / "right" are not places); places and other motion compete by length ("walking
#: along the sidewalk" is motion, "standing" + "on the sidewalk" motion and place, "on the pedestrian
#: crossing" a place); bare "moving" / "turning" come last.
_PATTERNS: tuple[tuple[str, int, str], ...] = (
    # crossing with a direction
    ("direction", 0, _ING_CROSS + _CROSS_OBJ + r" from " + _DIR + r" (?:to|towards|toward|over to|into) " + _DIR),
    ("direction", 0, _ING_CROSS + _CROSS_OBJ + r" " + _SIDE + r"[- ]to[- ]" + _SIDE),
    ("direction", 0, _ING_CROSS + _CROSS_OBJ + r" (?:over )?(?:to|towards|toward|onto) " + _DIR + r"(?! of\b)"),
    ("direction", 0, r"from " + _DIR + r" (?:to|towards|toward|over to|into) " + _DIR),
    ("direction", 0, r"\b" + _SIDE + r"[- ]to[- ]" + _SIDE),
    # ("not moving *to the left of the ego*": a place, not a direction)
    ("direction", 0, r"(?:walking|walks|moving|moves|heading|heads|going|goes|running|runs)(?: over)? "
                     r"(?:to|towards|toward) " + _DIR + r"(?! of\b)"),
    # turns and lane changes (directional vehicle motion)
    ("motion", 0, r"(?:turning|turns|turn|making|makes|doing|does|taking|takes|hanging|hangs|swinging|swings"
                  r"|veering|veers|bearing|bears|about to turn)(?: a| an)? (?:to the )?"
                  + _SIDE + r"(?! of\b)(?: turn)?"),
    ("motion", 0, _SIDE + r"(?:-turning| turning(?= (?:car|cars|vehicle|vehicles|truck|trucks|bus|buses|van|vans"
                          r"|suv|suvs|sedan|sedans|hatchback|hatchbacks|pickup|pickups)\b))"),
    ("motion", 0, r"(?:in the middle of |doing |making |taking )?(?:a |an )?" + _SIDE + r"[- ]hand turn"),
    ("motion", 0, r"(?:a |the )?" + _SIDE + r" turn"),
    ("motion", 0, r"(?<!not )(?:changing|changes|change|switching|switches|switch|merging|merges|merge|cutting|cuts"
                  r"|moving|moves|pulling|pulls|shifting|shifts|hopping|hops)(?: over)?(?: lanes?)?"
                  r"(?: (?:to|into|towards|toward|over to|in to)(?: the)?)? "
                  + _SIDE + r"(?:(?: into)?(?: the)? (?:next |adjacent )?lane)?"),
    ("motion", 0, r"(?<!not )(?:changing|changes|change|switching|switches|switch|merging|merges|merge|cutting|cuts"
                  r"|moving|moves|hopping|hops)(?: over)? (?:into|to|over to)(?: the)? (?:next |adjacent |other )?lane"
                  r"(?: (?:to|on) (?:the|its) " + _SIDE + r")?"),
    ("motion", 0, r"(?:a |doing a |making a )?lane[- ]change(?:s)?(?: (?:to|towards) the " + _SIDE + r")?"),
    ("motion", 0, r"lane[- ]changing(?: (?:to|towards) the " + _SIDE + r")?"),
    # places (before undirected motion: "on the pedestrian crossing" is a place)
    ("context", 1, r"(?:(?:on|at|in|near|using|across|along) )?(?:the |a )?"
                   r"(?:crosswalk|zebra(?: crossing)?|pedestrian crossing)"),
    ("context", 1, r"(?:(?:at|in|inside|within|near|by|next to|around|through|into|entering|approaching"
                   r"|in the middle of) )?(?:the |an |a )?(?:middle of the )?(?:" + voc.INTERSECTION_RX + r")"),
    ("context", 1, r"(?:(?:on|along|up on|at|near|by|onto) )?(?:the |a )?"
                   r"(?:sidewalk|pavement|footpath|walkway|footway)"),
    ("context", 1, r"(?:(?:by|at|next to|near|along|beside|against|on|to) )?(?:the )?"
                   r"(?:curb|kerb|curbside|kerbside|roadside|side of the road|edge of the road|shoulder)"),
    ("context", 1, r"(?:in|into|on) (?:the |a )?parking (?:lane|strip|spot|space|bay|lot)"),
    ("context", 1, r"(?:(?:in|from) the )?(?:oncoming|opposite|opposing)(?: direction)?(?: lane| traffic)?"),
    ("context", 1, r"(?:in (?:the|a) lane )?(?:driving|coming|heading|moving|going|travelling|traveling|approaching)"
                   r" towards? (?:us|me|ego|our car)"),
    ("context", 1, r"(?:approaching )?from the opposite direction"),
    ("context", 1, rf"(?:on|in|out on|along|down) (?:(?:a|{OWNER_WORDS}) )?"
                   r"(?:road|street|travel lane|lane|roadway|carriageway)"),
    ("sector", 1, r"(?:(?:on|to|at|off|in) (?:the |my |our |your )?)" + _SIDE
                  + r"(?:[- ]hand)?(?: side)?(?: lane)?(?: of (?:" + _EGO_ALT + r"|the (?:road|street)))?"),
    ("sector", 1, _SIDE + r" of " + _EGO),
    ("sector", 1, r"(?:(?:right|directly|straight|just|up) )?(?:in front(?: of " + _EGO + r")?"
                  r"|ahead(?: of " + _EGO + r")?|in the front)"),
    ("sector", 1, r"at (?:our|my|the) (?:back|rear)"),
    ("sector", 1, r"(?:(?:right|directly|just) )?(?:behind(?: " + _EGO + r")?|at the (?:back|rear)(?: of " + _EGO
                  + r")?|to the rear|following(?: behind)? " + _EGO + r")"),
    # undirected motion
    ("motion", 1, _ING_CROSS + _CROSS_OBJ),
    ("motion", 0, r"(?:going|driving|continuing|heading|moving|goes|drives|continues|heads|moves|travelling|traveling"
                  r"|cruising|carrying on) straight(?: ahead(?! of)| on(?! (?:the|my|our|your|its)\b))?"),
    ("motion", 1, r"(?:cruising|driving|going|travelling|traveling)(?: (?:down|along) the (?:road|street))?"),
    ("motion", 1, r"(?:slowing|slows|slow)(?: down| up)?|easing off|eases off|decelerating|decelerates|braking|brakes"
                  r"|hitting the brakes|losing speed|reducing (?:its )?speed"),
    ("motion", 1, r"speeding up|speeds up|accelerating|accelerates|picking up speed|gaining speed|pulling away"
                  r"|pulls away|starting to move(?: off)?|moving off|stepping on the gas|putting its foot down"),
    ("motion", 1, r"(?:coming|comes|came|pulling|pulls|braking) (?:to a |up to a )?(?:stop|halt)|stopping|stops"
                  r"|pulling up|pulls up|(?:braking|slowing) until it stands still|braking to a standstill"),
    ("motion", 1, r"(?:(?:just |stuck )?(?:stopped|halted|idling|queuing|queueing|stationary|at a standstill"
                  r"|not moving|not going anywhere|standing still|sitting still|motionless|sitting|waiting)(?: around)?"
                  r"(?: to cross| at the (?:light|lights|red light|signal|stop line)"
                  rf"| in (?:(?:{OWNER_WORDS}) )?(?:lane|traffic|line|queue))?)"),
    ("motion", 1, r"(?:sitting )?parked(?: up)?|sitting in a parking (?:spot|space|bay)"),
    ("motion", 1, r"reversing|reverses|backing (?:up|out)|backs (?:up|out)|in reverse(?: gear)?"
                  r"|(?:driving|going|moving) backwards?"),
    ("motion", 1, r"(?:walking|walks|strolling|strolls|jogging|jogs|running|runs|wandering|pacing)"
                  r"(?: (?:along|down|beside|on|by|up) (?:the )?(?:sidewalk|pavement|street|road|footpath|walkway))?"),
    ("motion", 1, r"(?:just )?(?:standing|stands|loitering|lingering)(?: still| there| around| by| waiting)?"),
    ("motion", 1, r"making (?:their|his|her|its|a|the) way across(?: (?:the|a) (?:street|road))?"),
    ("motion", 1, r"(?:making|taking|doing) a (?:turn|u-turn)|turning (?:a corner|off)"),
    ("motion", 2, r"moving|moves|in motion|turning|turns"),
)

_COMPILED = tuple((kind, prio, re.compile(r"(?<![\w-])(?:" + rx + r")(?![\w-])")) for kind, prio, rx in _PATTERNS)


@dataclass(frozen=True)
class Span:
    """A matched part of the normalised text: ``[start, end)`` characters, its kind and text."""

    start: int
    end: int
    kind: str
    text: str


@dataclass(frozen=True)
class ParsedQuery:
    """A query split into the parts the engine scores separately.

    Attributes:
        text: the query as given.
        normalised: lower-cased, punctuation-free text the spans index into.
        categories: node categories the subject allows (``types.CATEGORIES`` values); empty = any.
        subtype: the subtype named ("SUV", "truck", "car" for a passenger car, "child", "stop sign", ...)
            or ``None``.
        noun: the subject noun in the singular ("SUV", "pedestrian"), ``""`` when none was recognised.
        colors: colours not tied to a garment (vehicle body, street furniture, unordered clothing),
            captioner names.
        upper_color, lower_color: garment colours of a person ("red shirt" -> upper ``"red"``).
        appearance: text describing what the object looks like ("black car"), ``""`` when none.
        appearance_extra: the appearance words beyond the subject noun and connectives ("black"; ``""``
            for a bare "car"): what the appearance text says that the category alone does not.
        motion: the motion phrase as written ("turning left", "crossing from left to right"), or ``""``.
        crossing_direction: ``"left_to_right"`` / ``"right_to_left"`` when a crossing direction was given.
        sector: ego-relative location phrase ("on the right"), or ``""``.
        context: map-context location phrase ("at the intersection"), or ``""``.
        group: the query asks for every matching object ("all crossing pedestrians", plurals).
        spans: the motion / direction / sector / context spans found.
        excluded_colors: colours the query rules out ("not red"), captioner names.
    """

    text: str
    normalised: str
    categories: tuple[str, ...]
    subtype: str | None
    noun: str
    colors: tuple[str, ...]
    upper_color: str | None
    lower_color: str | None
    appearance: str
    appearance_extra: str
    motion: str
    crossing_direction: str | None
    sector: str
    context: str
    group: bool
    spans: tuple[Span, ...] = ()
    excluded_colors: tuple[str, ...] = ()

    @property
    def location(self) -> str:
        """Sector and context phrases together ("on the left at the intersection")."""
        return " ".join(p for p in (self.sector, self.context) if p)

    @property
    def motion_text(self) -> str:
        """What to embed for the motion part: the subject noun and the motion phrase ("car turning left")."""
        if not self.motion:
            return ""
        return f"{self.noun} {self.motion}" if self.noun else self.motion

    @property
    def named_colors(self) -> tuple[str, ...]:
        """Every colour the query names (garment colours included)."""
        return tuple(c for c in (self.upper_color, self.lower_color, *self.colors) if c)

    @property
    def has_appearance(self) -> bool:
        return bool(self.appearance or self.categories or self.named_colors or self.excluded_colors)

    def subject(self) -> str:
        """A singular noun phrase for messages ("black car", "pedestrian in a red top")."""
        words = []
        if self.colors and not (self.upper_color or self.lower_color):
            words.append(" and ".join(self.colors))
        words.append(self.noun or "object")
        phrase = " ".join(words)
        garments = []
        if self.upper_color:
            garments.append(f"a {self.upper_color} top")
        if self.lower_color:
            garments.append(f"{self.lower_color} trousers")
        if garments:
            phrase += " in " + " and ".join(garments)
        if self.excluded_colors:
            phrase += " that is not " + " or ".join(self.excluded_colors)
        return phrase


def normalise(text: str) -> str:
    """Lower case; curly quotes straightened; punctuation except hyphens and apostrophes turned into spaces."""
    text = text.lower().replace("\u2019", "'").replace("\u2018", "'")
    text = re.sub(r"[^\w\s'-]", " ", text)
    text = re.sub(r"(?<!\w)['-]|['-](?!\w)", " ", text)
    return re.sub(r"\s+", " ", text).strip()


def find_spans(normalised: str) -> tuple[Span, ...]:
    """Non-overlapping motion / direction / sector / context spans of ``normalised`` text, in text order."""
    found = []
    for kind, prio, rx in _COMPILED:
        for m in rx.finditer(normalised):
            if m.end() > m.start():
                found.append((prio, -(m.end() - m.start()), m.start(), m.end(), kind))
    found.sort()
    taken: list[tuple[int, int, str]] = []
    for _, _, start, end, kind in found:
        if all(end <= s or start >= e for s, e, _ in taken):
            taken.append((start, end, kind))
    taken.sort()
    return tuple(Span(s, e, k, normalised[s:e]) for s, e, k in taken)


def crossing_direction(phrase: str) -> str | None:
    """``"left_to_right"`` / ``"right_to_left"`` from a direction phrase, else ``None``.

    "from the left to the right", "left-to-right", "over to the right side", "heading to the left".
    """
    sides = re.findall(r"\b(left|right)\b", phrase)
    if not sides:
        return None
    if (len(sides) >= 2 and re.search(r"\bfrom\b|\bto\b", phrase)
            and re.search(r"(left|right)\W+(?:\w+\W+){0,3}?(?:to|towards|toward|into)\b", phrase)):
        target = sides[1]
    else:
        target = sides[-1]
    return "left_to_right" if target == "right" else "right_to_left"


def _residual(normalised: str, spans: tuple[Span, ...]) -> str:
    """``normalised`` with the spans blanked out (a ``|`` keeps words of both sides from joining)."""
    out = list(normalised)
    for span in spans:
        out[span.start : span.end] = "|" * (span.end - span.start)
    return re.sub(r"\|+", " | ", "".join(out))


_NOUN_RX = re.compile(r"(?<![\w-])(" + "|".join(sorted(map(re.escape, NOUNS), key=len, reverse=True)) + r")(?![\w-])")
_COLOR_ALTERNATIVES = "|".join(sorted(map(re.escape, COLOR_SYNONYMS), key=len, reverse=True))
_COLOR_RX = re.compile(r"(?<![\w-])(" + _COLOR_ALTERNATIVES + r")(?![\w-])")
_GARMENT_RX = re.compile(
    r"(?<![\w-])("
    + "|".join(sorted(map(re.escape, UPPER_GARMENTS + LOWER_GARMENTS), key=len, reverse=True))
    + r")(?![\w-])"
)


_NEGATION = r"(?:not|isn't|isnt|aren't|arent|never|neither|non|other than|anything but|but not|except(?: for)?)"
_COLOR_WORD = f"(?:{_COLOR_ALTERNATIVES})"
_NEGATED_COLOR_RX = re.compile(
    r"(?<![\w-])" + _NEGATION + r"(?:[- ](?:a|an|the|in|wearing|dressed in|painted|coloured|colored))*[- ]"
    + _COLOR_WORD + r"(?: (?:or|nor) " + _COLOR_WORD + r")*(?![\w-])(?: ones?(?![\w-]))?"
)

_COLOR_IN_NEGATION_RX = re.compile(r"(?<![a-z])(" + _COLOR_ALTERNATIVES + r")(?![a-z])")  # "non-white" too


def _negated_colours(residual: str) -> tuple[str, tuple[str, ...]]:
    """``(residual without the negated colour phrases, the colours they rule out)`` ("not red or white")."""
    excluded: list[str] = []
    for m in _NEGATED_COLOR_RX.finditer(residual):
        for word in _COLOR_IN_NEGATION_RX.findall(m.group(0)):
            if COLOR_SYNONYMS[word] not in excluded:
                excluded.append(COLOR_SYNONYMS[word])
    return _NEGATED_COLOR_RX.sub(" | ", residual), tuple(excluded)


def _colours(residual: str) -> tuple[tuple[str, ...], str | None, str | None]:
    """``(unordered colours, upper colour, lower colour)`` of the appearance words.

    A colour belongs to a garment when a garment word follows within three words, before the next
    colour and the next removed span ("red shirt", "blue denim jeans"); other colours are unordered
    ("a red car", "dressed in red").
    """
    colours = [(m.start(), m.end(), COLOR_SYNONYMS[m.group(1)]) for m in _COLOR_RX.finditer(residual)]
    unordered: list[str] = []
    upper = lower = None
    for i, (_, end, name) in enumerate(colours):
        stop = colours[i + 1][0] if i + 1 < len(colours) else len(residual)
        segment = residual[end:stop].split("|", 1)[0]
        found = _GARMENT_RX.search(segment)
        garment = found.group(1) if found and len(segment[: found.start()].split()) <= 3 else None
        if garment in UPPER_GARMENTS and upper is None:
            upper = name
        elif garment in LOWER_GARMENTS and lower is None:
            lower = name
        elif name not in unordered:
            unordered.append(name)
    return tuple(unordered), upper, lower


_ACRONYMS = {"suv": "SUV", "suvs": "SUVs"}


def parse_query(text: str) -> ParsedQuery:
    """Split a free-form grounding query into its parts (module docstring).

    Raises:
        ValueError: the query is empty.
    """
    if not text or not text.strip():
        raise ValueError("empty grounding query")
    norm = normalise(_DEICTIC_RX.sub(" ", text.lower()))
    spans = find_spans(norm)
    residual, excluded = _negated_colours(_residual(norm, spans))

    nouns = [(m.start(), m.group(1)) for m in _NOUN_RX.finditer(residual)]
    noun: Noun | None = None
    plural = False
    if nouns:
        noun, plural = NOUNS[nouns[0][1]]
    padded = f" {norm} "
    group = plural or any(f" {w} " in padded for w in GROUP_WORDS)

    colors, upper, lower = _colours(residual)
    if noun is not None and noun.categories != ("pedestrian",) and (upper or lower):
        # garment words on a vehicle query ("a car with a red top"?) are just colours
        colors = tuple(dict.fromkeys((*colors, *(c for c in (upper, lower) if c))))
        upper = lower = None

    motion_spans = [s for s in spans if s.kind in ("motion", "direction")]
    direction = None
    for span in spans:
        if span.kind == "direction":
            direction = crossing_direction(span.text)
    motion = " ".join(s.text for s in motion_spans)
    if direction and not re.search(r"cross", motion):
        motion = (f"crossing {motion}"
                  if not re.match(r"(walking|walks|moving|moves|heading|heads|going|goes|running|runs)\b", motion)
                  else motion)
    sector = " ".join(s.text for s in spans if s.kind == "sector")
    context = " ".join(s.text for s in spans if s.kind == "context")

    words = [w for w in residual.replace("|", " ").split() if w not in FILLERS]
    # drop a dangling "and" / "in" / "with" at the ends left by removed spans
    while words and words[-1] in ("and", "in", "with", "on", "at", "to", "by"):
        words.pop()
    while words and words[0] in ("and", "in", "with", "on", "at", "to", "by"):
        words.pop(0)
    appearance = " ".join(_ACRONYMS.get(w, w) for w in words)
    extra_text = _NOUN_RX.sub(" ", " ".join(words))
    extra = " ".join(w for w in extra_text.split() if w not in CONNECTIVES)

    return ParsedQuery(
        text=text,
        normalised=norm,
        categories=noun.categories if noun else (),
        subtype=noun.subtype if noun else None,
        noun=("SUV" if noun and noun.singular == "suv" else noun.singular) if noun else "",
        colors=colors,
        upper_color=upper,
        lower_color=lower,
        appearance=appearance,
        appearance_extra=extra,
        motion=motion,
        crossing_direction=direction,
        sector=sector,
        context=context,
        group=group,
        spans=spans,
        excluded_colors=excluded,
    )
