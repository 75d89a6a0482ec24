"""Free-form wordings of object descriptions for the grounding benchmark.

A ``Description`` (``benchmark.py``) is a set of constraints -- category, body style, colours,
motion, location. This module turns one into text in one of several *styles*, drawing words from
synonym tables with a seeded ``numpy.random.Generator``:

* ``terse``        "red SUV turning left at the junction"
* ``definite``     "the red SUV turning left at the intersection"
* ``relative``     "the red SUV that's making a left turn on my left"
* ``polite``       "Could you please show me the red SUV turning left?"
* ``imperative``   "Highlight the red SUV that is turning left."
* ``question``     "Where is the red SUV turning left at the crossroads?"
* ``descriptive``  "I'm looking for a red SUV; it is turning left, at the intersection."
* ``colloquial``   "that red ride hanging a left by the crossroads"

Group descriptions ("all pedestrians crossing the street") have their own styles (``GROUP_STYLES``).

The phrase tables are written for the benchmark and deliberately do not copy the motion codebook's
prototype phrases (``vocabulary.py``), so grounding is tested on wordings the aligner never saw. A few
meanings are worded as *terms* that cover several auto-label classes (``MOTION_TERMS``): "crossing the
street" covers both crossing directions, "turning" both turn directions, "stationary" both stopped and
parked vehicles; the benchmark's uniqueness check uses the same class sets.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.language.appearance.captioner import article
from simsplat_core.scenario import vocabulary as voc

#: Motion terms: term -> (agent kind, auto-label classes it denotes).
MOTION_TERMS: dict[str, tuple[str, frozenset[str]]] = {
    voc.TURNING_LEFT: ("vehicle", frozenset({voc.TURNING_LEFT})),
    voc.TURNING_RIGHT: ("vehicle", frozenset({voc.TURNING_RIGHT})),
    "turning_any": ("vehicle", frozenset({voc.TURNING_LEFT, voc.TURNING_RIGHT})),
    voc.GOING_STRAIGHT: ("vehicle", frozenset({voc.GOING_STRAIGHT})),
    voc.CHANGING_LANE_LEFT: ("vehicle", frozenset({voc.CHANGING_LANE_LEFT})),
    voc.CHANGING_LANE_RIGHT: ("vehicle", frozenset({voc.CHANGING_LANE_RIGHT})),
    voc.SLOWING_DOWN: ("vehicle", frozenset({voc.SLOWING_DOWN})),
    voc.SPEEDING_UP: ("vehicle", frozenset({voc.SPEEDING_UP})),
    voc.STOPPING: ("vehicle", frozenset({voc.STOPPING})),
    voc.STOPPED: ("vehicle", frozenset({voc.STOPPED})),
    voc.PARKED: ("vehicle", frozenset({voc.PARKED})),
    "stationary_vehicle": ("vehicle", frozenset({voc.STOPPED, voc.PARKED})),
    voc.REVERSING: ("vehicle", frozenset({voc.REVERSING})),
    voc.CROSSING_LEFT_TO_RIGHT: ("pedestrian", frozenset({voc.CROSSING_LEFT_TO_RIGHT})),
    voc.CROSSING_RIGHT_TO_LEFT: ("pedestrian", frozenset({voc.CROSSING_RIGHT_TO_LEFT})),
    "crossing_any": ("pedestrian", frozenset({voc.CROSSING, voc.CROSSING_LEFT_TO_RIGHT, voc.CROSSING_RIGHT_TO_LEFT})),
    voc.WALKING_ALONG: ("pedestrian", frozenset({voc.WALKING_ALONG})),
    voc.STANDING: ("pedestrian", frozenset({voc.STANDING})),
}

#: The terms that name an auto-label class exactly, and the broader terms that also cover it.
EXACT_TERM: dict[str, str] = {
    voc.TURNING_LEFT: voc.TURNING_LEFT,
    voc.TURNING_RIGHT: voc.TURNING_RIGHT,
    voc.GOING_STRAIGHT: voc.GOING_STRAIGHT,
    voc.CHANGING_LANE_LEFT: voc.CHANGING_LANE_LEFT,
    voc.CHANGING_LANE_RIGHT: voc.CHANGING_LANE_RIGHT,
    voc.SLOWING_DOWN: voc.SLOWING_DOWN,
    voc.SPEEDING_UP: voc.SPEEDING_UP,
    voc.STOPPING: voc.STOPPING,
    voc.STOPPED: voc.STOPPED,
    voc.PARKED: voc.PARKED,
    voc.REVERSING: voc.REVERSING,
    voc.CROSSING_LEFT_TO_RIGHT: voc.CROSSING_LEFT_TO_RIGHT,
    voc.CROSSING_RIGHT_TO_LEFT: voc.CROSSING_RIGHT_TO_LEFT,
    voc.CROSSING: "crossing_any",
    voc.WALKING_ALONG: voc.WALKING_ALONG,
    voc.STANDING: voc.STANDING,
}
BROADER_TERMS: dict[str, tuple[str, ...]] = {
    voc.TURNING_LEFT: ("turning_any",),
    voc.TURNING_RIGHT: ("turning_any",),
    voc.STOPPED: ("stationary_vehicle",),
    voc.PARKED: ("stationary_vehicle",),
    voc.CROSSING_LEFT_TO_RIGHT: ("crossing_any",),
    voc.CROSSING_RIGHT_TO_LEFT: ("crossing_any",),
}

# participle phrases ("the car ___"); colloquial ones are used by the colloquial style only
_MOTION: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    voc.TURNING_LEFT: (
        ("turning left", "making a left turn", "taking a left", "turning to the left"),
        ("hanging a left", "swinging left", "taking a left"),
    ),
    voc.TURNING_RIGHT: (
        ("turning right", "making a right turn", "taking a right", "turning to the right"),
        ("hanging a right", "swinging right", "taking a right"),
    ),
    "turning_any": (("turning", "making a turn", "turning a corner"), ("turning off", "taking a turn")),
    voc.GOING_STRAIGHT: (
        ("going straight", "driving straight ahead", "heading straight on", "continuing straight"),
        ("going straight through", "cruising straight on"),
    ),
    voc.CHANGING_LANE_LEFT: (
        ("changing lanes to the left", "moving over into the left lane", "switching to the lane on its left"),
        ("cutting over to the left lane", "hopping into the left lane"),
    ),
    voc.CHANGING_LANE_RIGHT: (
        ("changing lanes to the right", "moving over into the right lane", "switching to the lane on its right"),
        ("cutting over to the right lane", "hopping into the right lane"),
    ),
    voc.SLOWING_DOWN: (("slowing down", "decelerating", "reducing its speed"), ("easing off", "slowing up")),
    voc.SPEEDING_UP: (("speeding up", "accelerating", "picking up speed"), ("stepping on the gas", "speeding up")),
    voc.STOPPING: (
        ("coming to a stop", "braking to a halt", "pulling up to a stop"),
        ("pulling up", "braking to a standstill"),
    ),
    voc.STOPPED: (
        ("stopped in its lane", "waiting in the lane", "standing still in traffic"),
        ("just sitting in the lane", "stuck waiting in its lane"),
    ),
    voc.PARKED: ((voc.PARKED, "parked at the curb", "parked by the side of the road"), ("parked up", "sitting parked")),
    "stationary_vehicle": (("not moving", "stationary", "standing still"), ("not going anywhere", "sitting still")),
    voc.REVERSING: ((voc.REVERSING, "backing up", "driving backwards"), ("backing out", "going in reverse")),
    voc.CROSSING_LEFT_TO_RIGHT: (
        (
            "crossing the street from left to right",
            "walking across the road from left to right",
            "crossing from the left to the right",
        ),
        ("heading across the road left to right", "crossing over left to right"),
    ),
    voc.CROSSING_RIGHT_TO_LEFT: (
        (
            "crossing the street from right to left",
            "walking across the road from right to left",
            "crossing from the right to the left",
        ),
        ("heading across the road right to left", "crossing over right to left"),
    ),
    "crossing_any": (
        ("crossing the street", "walking across the road", "crossing the road"),
        ("heading across the street", "making their way across the road"),
    ),
    voc.WALKING_ALONG: (
        ("walking along the sidewalk", "walking down the pavement", "walking beside the road"),
        ("strolling along the sidewalk", "wandering down the pavement"),
    ),
    voc.STANDING: (
        ("standing still", "standing and waiting", "not moving"),
        ("just standing around", "waiting around"),
    ),
}

_SECTOR: dict[str, tuple[str, ...]] = {
    voc.IN_FRONT_OF_EGO: ("in front of us", "ahead of us", "in front of me", "up ahead", "ahead of the ego car"),
    voc.BEHIND_EGO: ("behind us", "behind me", "behind the ego car", "at our rear"),
    voc.LEFT_OF_EGO: ("on my left", "to our left", "on the left-hand side", "to the left of the ego car"),
    voc.RIGHT_OF_EGO: ("on my right", "to our right", "on the right-hand side", "to the right of the ego car"),
}
_CONTEXT: dict[str, tuple[str, ...]] = {
    voc.AT_THE_INTERSECTION: ("at the intersection", "in the junction", "at the crossroads", "inside the intersection"),
    voc.ON_THE_CROSSWALK: ("on the crosswalk", "on the zebra crossing", "in the crosswalk"),
    voc.ON_THE_SIDEWALK: ("on the sidewalk", "on the pavement", "on the footpath"),
    voc.BY_THE_CURB: ("by the curb", "at the roadside", "next to the curb", "along the kerb"),
    voc.IN_THE_ONCOMING_LANE: ("in the oncoming lane", "in the opposite lane", "in the lane coming towards us"),
}
#: Location contexts a description may name ("on the road" is true of almost everything: never used).
DESCRIBABLE_CONTEXTS: tuple[str, ...] = tuple(_CONTEXT)

_COLOR: dict[str, tuple[str, ...]] = {"gray": ("gray", "grey")}

# vehicle nouns: specific body styles, and generic nouns by body style (a bus is not a "car")
_SUBTYPE_NOUN: dict[str, tuple[str, ...]] = {
    "sedan": ("sedan", "saloon car"),
    "hatchback": ("hatchback",),
    "SUV": ("SUV", "sport utility vehicle"),
    "van": ("van",),
    "pickup truck": ("pickup truck", "pickup", "pick-up"),
    "truck": ("truck", "lorry"),
    "bus": ("bus",),
}
_PLURAL = {
    "bus": "buses",
    "person": "people",
    "passer-by": "passers-by",
    "individual": "individuals",
}
_CAR_LIKE = ("sedan", "hatchback", "SUV")
_GENERIC_CAR = ("car", "vehicle")
_GENERIC_OTHER = ("vehicle",)
_COLLOQUIAL_CAR = ("ride", "car", "motor")
_PEDESTRIAN_NOUN = ("pedestrian", "person", "walker", "passer-by", "individual")
_COLLOQUIAL_PEDESTRIAN = ("person", "walker", "someone")
_UPPER = ("top", "shirt", "jacket", "sweater", "hoodie")
_LOWER = ("pants", "trousers")

#: Styles of single-target (and no-match) descriptions and of group descriptions.
SINGLE_STYLES: tuple[str, ...] = (
    "terse",
    "definite",
    "relative",
    "polite",
    "imperative",
    "question",
    "descriptive",
    "colloquial",
)
GROUP_STYLES: tuple[str, ...] = ("all", "every", "request", "question", "plural")


@dataclass(frozen=True)
class Wording:
    """The constraints to put in words (a ``Description`` without the matching logic).

    Attributes:
        category: ``"vehicle"`` or ``"pedestrian"``.
        subtype: specific vehicle body style, or ``None`` for a generic noun.
        generic_subtypes: body styles the generic noun has to fit ("car" only for passenger cars).
        color: vehicle colour; upper / lower: pedestrian clothing colours.
        motion: ``MOTION_TERMS`` key; sector / context: location classes (``vocabulary.py`` names).
    """

    category: str
    subtype: str | None = None
    generic_subtypes: tuple[str, ...] = ()
    color: str | None = None
    upper: str | None = None
    lower: str | None = None
    motion: str | None = None
    sector: str | None = None
    context: str | None = None


def _pick(rng: np.random.Generator, options: tuple[str, ...] | list[str]) -> str:
    return options[int(rng.integers(len(options)))]


def plural(noun: str) -> str:
    """Plural of a noun of the tables (last word inflected)."""
    if noun in _PLURAL:
        return _PLURAL[noun]
    head, _, last = noun.rpartition(" ")
    last = _PLURAL.get(last, last + ("es" if last.endswith(("s", "x", "ch", "sh")) else "s"))
    return f"{head} {last}".strip()


def color_word(color: str, rng: np.random.Generator) -> str:
    return _pick(rng, _COLOR.get(color, (color,)))


def vehicle_noun(w: Wording, rng: np.random.Generator, colloquial: bool = False) -> str:
    if w.subtype is not None:
        return _pick(rng, _SUBTYPE_NOUN.get(w.subtype, (w.subtype,)))
    car_like = bool(w.generic_subtypes) and all(s in _CAR_LIKE for s in w.generic_subtypes)
    if colloquial and car_like:
        return _pick(rng, _COLLOQUIAL_CAR)
    return _pick(rng, _GENERIC_CAR if car_like else _GENERIC_OTHER)


def garments(w: Wording, rng: np.random.Generator, plural_form: bool = False) -> str:
    """Post-modifier naming clothing colours: ``"in a red top and blue pants"`` / ``"wearing red jackets"``."""
    if w.upper is None and w.lower is None:
        return ""
    parts = []
    if w.upper is not None:
        top = _pick(rng, _UPPER)
        c = color_word(w.upper, rng)
        parts.append(f"{c} {plural(top)}" if plural_form else f"{article(c)} {c} {top}")
    if w.lower is not None:
        parts.append(f"{color_word(w.lower, rng)} {_pick(rng, _LOWER)}")
    verb = _pick(rng, ("in", "wearing", "with") if w.upper is not None else ("in", "wearing"))
    return f"{verb} {' and '.join(parts)}"


def noun_phrase(w: Wording, rng: np.random.Generator, colloquial: bool = False, plural_form: bool = False) -> str:
    """The description's subject without determiner: ``"red SUV"``, ``"person in a red top"``."""
    if w.category == "pedestrian":
        noun = _pick(rng, _COLLOQUIAL_PEDESTRIAN if colloquial else _PEDESTRIAN_NOUN)
        if noun == "someone" and plural_form:
            noun = "person"
        noun = plural(noun) if plural_form else noun
        return " ".join(p for p in (noun, garments(w, rng, plural_form)) if p)
    noun = vehicle_noun(w, rng, colloquial)
    noun = plural(noun) if plural_form else noun
    return " ".join(p for p in ((color_word(w.color, rng) if w.color else ""), noun) if p)


def motion_phrase(term: str | None, rng: np.random.Generator, colloquial: bool = False) -> str:
    if term is None:
        return ""
    plain, casual = _MOTION[term]
    return _pick(rng, plain + casual if colloquial else plain)


def location_phrase(sector: str | None, context: str | None, rng: np.random.Generator) -> str:
    parts = []
    if sector is not None:
        parts.append(_pick(rng, _SECTOR[sector]))
    if context is not None:
        parts.append(_pick(rng, _CONTEXT[context]))
    if len(parts) == 2 and rng.random() < 0.5:
        parts.reverse()
    return " ".join(parts)


def _join(*parts: str) -> str:
    return " ".join(p for p in parts if p).replace(" ,", ",")


def _definite(np_: str) -> str:
    return np_ if np_.startswith("someone") else f"the {np_}"


def _indefinite(np_: str) -> str:
    return np_ if np_.startswith("someone") else f"{article(np_)} {np_}"


def _rel(w: Wording, rng: np.random.Generator) -> str:
    return _pick(rng, ("who is", "who's", "that is") if w.category == "pedestrian"
                 else ("that is", "that's", "which is"))


def realise(w: Wording, style: str, rng: np.random.Generator) -> str:
    """One wording of a single-object description (or a no-match description) in ``style``."""
    colloquial = style == "colloquial"
    np_ = noun_phrase(w, rng, colloquial)
    mot = motion_phrase(w.motion, rng, colloquial)
    loc = location_phrase(w.sector, w.context, rng)
    # put the location before the motion now and then ("the car on my left turning right"); always for an
    # undirected turn, where "turning to the left of the ego car" would read as a direction
    loc_first = w.motion == "turning_any" and w.sector is not None
    mot_loc = _join(loc, mot) if (loc and mot and (loc_first or rng.random() < 0.3)) else _join(mot, loc)
    if style == "terse":
        return _join(np_, mot_loc)
    if style == "definite":
        return _join(_definite(np_), mot_loc)
    if style == "relative":
        if not mot_loc:
            return _definite(np_)
        return _join(_definite(np_), _rel(w, rng), mot_loc)
    if style == "polite":
        lead = _pick(
            rng,
            ("Could you please show me", "Would you mind pointing out", "Can you please find", "Please highlight",
             "Please select"),
        )
        end = "?" if lead.split()[0] in ("Could", "Would", "Can") else "."
        return _join(lead, _definite(np_), mot_loc) + end
    if style == "imperative":
        lead = _pick(rng, ("Find", "Select", "Segment", "Show me", "Locate", "Highlight", "Mark"))
        body = (_join(_definite(np_), _rel(w, rng), mot_loc) if mot and rng.random() < 0.5
                else _join(_definite(np_), mot_loc))
        return f"{lead} {body}."
    if style == "question":
        lead = _pick(rng, ("Where is", "Can you spot", "Do you see", "Which one is"))
        return _join(lead, _definite(np_), mot_loc) + "?"
    if style == "descriptive":
        if mot and loc and not loc_first:
            return _pick(
                rng,
                (
                    f"I'm looking for {_indefinite(np_)} that is {mot}, {loc}.",
                    f"There is {_indefinite(np_)} {loc}; it is {mot}. That one.",
                    f"The one I mean is {_indefinite(np_)} {mot} {loc}.",
                ),
            )
        rest = mot_loc
        if rest:
            return _pick(
                rng,
                (
                    f"I'm looking for {_indefinite(np_)} {rest}.",
                    f"The one I mean is {_indefinite(np_)} {rest}.",
                    f"There is {_indefinite(np_)} {rest}; that one.",
                ),
            )
        return _pick(rng, (f"I'm looking for {_indefinite(np_)}.", f"The one I mean is {_indefinite(np_)}."))
    if style == "colloquial":
        lead = _pick(rng, ("that", "yo, the", "the", "where's that"))
        if np_.startswith("someone"):
            lead = _pick(rng, ("", "there's", "look,"))
        tail = _pick(rng, ("", " over there", " right there"))
        text = _join(lead, np_, mot_loc) + tail
        return text + ("?" if lead.startswith("where") else "")
    raise ValueError(f"unknown style {style!r}; use one of {SINGLE_STYLES}")


def realise_group(w: Wording, style: str, rng: np.random.Generator) -> str:
    """One wording of a group description ("all pedestrians crossing the street") in ``style``."""
    np_pl = noun_phrase(w, rng, plural_form=True)
    mot = motion_phrase(w.motion, rng).replace(" its ", " their ").replace(" its", " their")
    loc = location_phrase(w.sector, w.context, rng)
    mot_loc = _join(mot, loc)
    are = "who are" if w.category == "pedestrian" else "that are"
    if style == "all":
        return _join(_pick(rng, ("all", "all the")), np_pl, mot_loc)
    if style == "every":
        np_sg = noun_phrase(w, rng)
        return _join(_pick(rng, ("every", "each")), np_sg, mot_loc)
    if style == "request":
        lead = _pick(rng, ("Show me all the", "Highlight all", "Select every one of the", "Please find all"))
        body = _join(lead, np_pl, are, mot_loc) if mot_loc else _join(lead, np_pl)
        return body + "."
    if style == "question":
        if mot_loc:
            return _join("Which", np_pl, "are", mot_loc) + "?"
        return _join("Where are all the", np_pl) + "?"
    if style == "plural":
        return _join("the", np_pl, mot_loc)
    raise ValueError(f"unknown group style {style!r}; use one of {GROUP_STYLES}")


__all__ = [
    "BROADER_TERMS",
    "DESCRIBABLE_CONTEXTS",
    "EXACT_TERM",
    "GROUP_STYLES",
    "MOTION_TERMS",
    "SINGLE_STYLES",
    "Wording",
    "location_phrase",
    "motion_phrase",
    "noun_phrase",
    "plural",
    "realise",
    "realise_group",
]
