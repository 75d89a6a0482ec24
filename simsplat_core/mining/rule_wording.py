"""Words of the rule-based client's proposals: how objects, assets, distances and speeds are said, and the
sentence forms of every proposal kind.

* :func:`referring_phrase` -- a definite description of a scene object as people type it ("the white SUV
  ahead of us", "the parked silver van by the curb", "the pedestrian in a red top on the right sidewalk"):
  its caption, plus the grounded facts (location sector, map context, motion) needed to tell it from
  objects with the same caption, sometimes one more for a natural touch; ``None`` when nothing tells it apart.
  Location words are the behaviour vocabulary's own phrasings (``scenario.vocabulary``), those that read as a
  relative clause after a noun.
* :func:`asset_phrase`, :func:`distance_phrase`, :func:`speed_phrase`, :func:`duration_phrase` -- indefinite
  asset descriptions from the bank's assets, and quantities with varied units and spellings.
* :data:`FORMS` -- several sentence forms per proposal kind (imperative, declarative, polite, colloquial; with
  synonyms), filled by :func:`realise`.

All choices draw from a ``numpy.random.Generator``, so wording is deterministic for a seed.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from simsplat_core.editing.behaviours.registry import PROPOSAL_FORMS
from simsplat_core.editing.commands import SPEED_UNITS
from simsplat_core.language.appearance.captioner import article
from simsplat_core.mining.scene_fact_records import AgentFacts, AssetFacts, SceneFacts
from simsplat_core.scenario import vocabulary as voc

#: Phrases of a vocabulary class usable after a noun: they start with a preposition and name no motion.
_RELATIVE = re.compile(r"^(?:in|on|at|by|to|behind|next to|out on)\b")
_NO_MOTION = re.compile(r"cross(?!walk)|follow|approach|driving")
#: Phrases the edit parser reads as a placement ("behind me": behind an object called "me").
_PLACEMENT_LIKE = re.compile(r"^behind me\b")


def _relative_phrases(vocabulary: voc.Vocabulary, name: str) -> tuple[str, ...]:
    """The class's prototype and query phrasings that read as a relative clause ("ahead of us" is kept as the
    sector words' one exception: it starts with an adverb); never the ego spelled out ("the ego car")."""
    phrases = vocabulary[name].prototypes + vocabulary[name].queries
    keep = [p for p in phrases if (_RELATIVE.match(p) or p.startswith("ahead of")) and not _NO_MOTION.search(p)
            and not _PLACEMENT_LIKE.match(p) and "ego" not in p and " a " not in f" {p} "]
    return tuple(dict.fromkeys(keep))


#: Location sector -> phrases ("ahead of us", "on my left", "to the right of our car", ...).
SECTOR_PHRASES: dict[str, tuple[str, ...]] = {n: _relative_phrases(voc.LOCATION_SECTOR, n)
                                              for n in voc.LOCATION_SECTOR.names}
#: Map context -> phrases ("in the oncoming lane", "by the curb", "on the pavement", ...).
CONTEXT_PHRASES: dict[str, tuple[str, ...]] = {n: _relative_phrases(voc.LOCATION_CONTEXT, n)
                                               for n in voc.LOCATION_CONTEXT.names}
#: Motion class -> adjectives before the noun ("the parked van") and phrases after it ("turning left"). Classes
#: whose words read as an edit ("slowing down", "changing lanes") are never said.
MOTION_BEFORE: dict[str, tuple[str, ...]] = {voc.PARKED: (voc.PARKED,), voc.STOPPED: (voc.STOPPED,),
                                             voc.STANDING: (voc.STANDING,), voc.WALKING_ALONG: ("walking",)}
MOTION_AFTER: dict[str, tuple[str, ...]] = {
    voc.TURNING_LEFT: ("turning left",), voc.TURNING_RIGHT: ("turning right",),
    voc.GOING_STRAIGHT: ("going straight", "driving straight"),
    voc.CROSSING: ("crossing the road", "crossing the street"),
    voc.CROSSING_LEFT_TO_RIGHT: ("crossing the road", "crossing the street"),
    voc.CROSSING_RIGHT_TO_LEFT: ("crossing the road", "crossing the street")}
_CROSSING = (voc.CROSSING, voc.CROSSING_LEFT_TO_RIGHT, voc.CROSSING_RIGHT_TO_LEFT)
_SIDES = {voc.LEFT_OF_EGO: "left", voc.RIGHT_OF_EGO: "right"}
#: Qualifier sets tried to single an object out, fewest first.
_QUALIFIER_SETS: tuple[tuple[str, ...], ...] = ((), ("sector",), ("context",), ("motion",), ("context", "sector"),
                                                ("motion", "sector"), ("motion", "context"),
                                                ("motion", "context", "sector"))
#: Chance of naming one more (true) qualifier than needed.
EXTRA_QUALIFIER_P = 0.35


def pick(rng: np.random.Generator, options: Sequence[str]) -> str:
    return options[int(rng.integers(len(options)))]


def capitalised(text: str) -> str:
    return text[:1].upper() + text[1:]


# ---------------------------------------------------------------------------------------------- objects
def _motion_key(motion: str) -> str:
    return voc.CROSSING if motion in _CROSSING else motion


def _sayable(agent: AgentFacts, qualifier: str) -> bool:
    if qualifier == "sector":
        return bool(SECTOR_PHRASES.get(agent.sector))
    if qualifier == "context":
        return bool(CONTEXT_PHRASES.get(agent.context))
    return agent.motion in MOTION_BEFORE or agent.motion in MOTION_AFTER


def _tells_apart(agent: AgentFacts, other: AgentFacts, qualifiers: tuple[str, ...]) -> bool:
    return any((q == "sector" and agent.sector != other.sector) or (q == "context" and agent.context != other.context)
               or (q == "motion" and _motion_key(agent.motion) != _motion_key(other.motion)) for q in qualifiers)


def lookalikes(agent: AgentFacts, facts: SceneFacts) -> tuple[AgentFacts, ...]:
    """Other objects with the same caption (the ones a description must tell ``agent`` from)."""
    key = agent.caption.lower()
    return tuple(a for a in facts.agents if a.object_id != agent.object_id and a.caption.lower() == key)


def qualifiers_for(agent: AgentFacts, facts: SceneFacts) -> tuple[tuple[str, ...], ...]:
    """The smallest sayable qualifier sets that tell ``agent`` from its :func:`lookalikes` (empty: none does)."""
    others = lookalikes(agent, facts)
    for size in range(4):
        found = tuple(q for q in _QUALIFIER_SETS if len(q) == size and all(_sayable(agent, x) for x in q)
                      and all(_tells_apart(agent, o, q) for o in others))
        if found:
            return found
    return ()


def _noun_phrase(agent: AgentFacts, rng: np.random.Generator) -> str:
    """The caption made definite, the head noun of a pedestrian sometimes "person"."""
    caption = agent.caption or f"a {agent.category}"
    words = caption.split(" ", 1)
    rest = words[1] if len(words) > 1 and words[0].lower() in ("a", "an") else caption
    if agent.kind == "pedestrian" and rest.startswith("pedestrian") and rng.random() < 0.4:
        rest = "person" + rest[len("pedestrian"):]
    return f"the {rest}"


def _location(agent: AgentFacts, with_sector: bool, with_context: bool, rng: np.random.Generator) -> str:
    side = _SIDES.get(agent.sector)
    if with_sector and with_context and agent.context == voc.ON_THE_SIDEWALK and side and rng.random() < 0.6:
        return f"on the {side} sidewalk"
    parts = []
    if with_context:
        parts.append(pick(rng, CONTEXT_PHRASES[agent.context]))
    if with_sector:
        parts.append(pick(rng, SECTOR_PHRASES[agent.sector]))
    return " ".join(parts)


def referring_phrase(agent: AgentFacts, facts: SceneFacts, rng: np.random.Generator) -> str | None:
    """A definite description of ``agent`` that tells it from its lookalikes (module docstring)."""
    options = qualifiers_for(agent, facts)
    if not options:
        return None
    chosen = set(options[int(rng.integers(len(options)))])
    spare = [q for q in ("sector", "context", "motion") if q not in chosen and _sayable(agent, q)]
    if spare and rng.random() < EXTRA_QUALIFIER_P:
        chosen.add(pick(rng, spare))
    noun = _noun_phrase(agent, rng)
    before = after = ""
    if "motion" in chosen:
        if agent.motion in MOTION_BEFORE:
            before = pick(rng, MOTION_BEFORE[agent.motion])
        else:
            after = pick(rng, MOTION_AFTER[agent.motion])
    if before:
        noun = noun.replace("the ", f"the {before} ", 1)
    where = _location(agent, "sector" in chosen, "context" in chosen, rng)
    return " ".join(p for p in (noun, after, where) if p)


def group_phrase(agent: AgentFacts, rng: np.random.Generator) -> str:
    """Every object with ``agent``'s caption: "all the orange traffic cones", "every orange traffic cone"."""
    caption = agent.caption or f"a {agent.category}"
    rest = caption.split(" ", 1)[1] if caption.split(" ", 1)[0].lower() in ("a", "an") else caption
    return pick(rng, (f"all the {plural(rest)}", f"every {rest}", f"the {plural(rest)}"))


def plural(noun: str) -> str:
    """English plural of a noun phrase's last word ("traffic cone" -> "traffic cones", "bus" -> "buses")."""
    head, _, last = noun.rpartition(" ")
    last = last + "es" if last.endswith(("s", "x", "ch", "sh")) else last + "s"
    return f"{head} {last}".strip()


# ---------------------------------------------------------------------------------------------- assets
#: Subtypes a person also calls "car".
CAR_SUBTYPES = ("sedan", "hatchback", "SUV", "car")


def asset_phrase(asset: AssetFacts, rng: np.random.Generator) -> str:
    """An indefinite description of ``asset`` as people ask for it: "a yellow sedan", "a car", "someone"."""
    if asset.category == "pedestrian":
        top = f"a person in a {asset.color} top" if asset.color else "a person"
        return pick(rng, ("a pedestrian", "a person", "someone", top))
    if asset.category == "vehicle":
        nouns = [asset.subtype, "car"] if asset.subtype in CAR_SUBTYPES else [asset.subtype]
        noun = pick(rng, nouns)
        phrase = f"{asset.color} {noun}" if asset.color and rng.random() < 0.6 else noun
        return f"{article(phrase)} {phrase}"
    phrase = f"{asset.color} {asset.subtype}" if asset.color and rng.random() < 0.5 else asset.subtype
    return f"{article(phrase)} {phrase}"


def row_phrase(asset: AssetFacts, count: int, rng: np.random.Generator) -> str:
    """Several static objects: "4 orange traffic cones", "a row of 3 cones"."""
    noun = plural(pick(rng, (asset.subtype, asset.subtype.split(" ")[-1])))
    noun = f"{asset.color} {noun}" if asset.color and rng.random() < 0.5 else noun
    return pick(rng, (f"{count} {noun}", f"a row of {count} {noun}"))


# ---------------------------------------------------------------------------------------------- quantities
def distance_phrase(metres: float, rng: np.random.Generator) -> str:
    value = int(round(metres))
    return pick(rng, (f"{value} m", f"{value} metres", f"{value} meters", f"{value}m"))


def speed_phrase(mps: float, rng: np.random.Generator) -> str:
    """``mps`` in km/h, mph or m/s, rounded as people say it (km/h and mph to 5, m/s to 1)."""
    unit = pick(rng, ("km/h", "mph", "m/s"))
    value = mps / SPEED_UNITS[unit]
    said = int(round(value)) if unit == "m/s" else int(5 * round(value / 5))
    return f"{max(said, 1)} {unit}"


def duration_phrase(seconds: float, rng: np.random.Generator) -> str:
    value = int(round(seconds))
    return pick(rng, (f"{value} s", f"{value} seconds", f"{value} secs")) if value != 1 else "1 second"


# ---------------------------------------------------------------------------------------------- sentence forms
#: Sentence forms per proposal kind. Slots: {T} a scene object (definite), {A} an asset (indefinite), {P} a
#: pedestrian asset, {R} a row of static objects, {d} a distance, {v} a speed, {t} a duration, {side} / {other}
#: "left" / "right" (the other side), {G} a group of scene objects.
FORMS: dict[str, tuple[str, ...]] = {
    # ------------------------------------------------------------------ add a vehicle
    "cut_in": (
        "Add {A} in the {side} lane {d} ahead and make it cut in to the {other}.",
        "Put {A} in the lane to our {side}, {d} ahead, and have it change lanes to the {other}.",
        "spawn {A} {d} ahead in the {side} lane that suddenly cuts in to the {other}",
        "Insert {A} in the {side}-hand lane about {d} in front of us and make it merge {other}.",
    ),
    "lead_brake": (
        "Add {A} {d} ahead of us in our lane and make it brake hard.",
        "Insert {A} in the ego lane {d} in front and have it stop suddenly.",
        "Place {A} {d} ahead in my lane and make it come to a sudden stop.",
        "Put {A} in our lane {d} ahead and have it slam on the brakes.",
    ),
    "oncoming": (
        "Add {A} in the oncoming lane {d} ahead.",
        "Put {A} in the opposite lane about {d} in front of us.",
        "Insert {A} {d} ahead in the lane of oncoming traffic.",
    ),
    "side_lane_fast": (
        "Add {A} in the {side} lane {d} ahead driving at {v}.",
        "Put {A} {d} ahead in the lane to our {side}, going {v}.",
    ),
    "tailgate": (
        "Add {A} {d} behind {T}.",
        "Put {A} right behind {T}.",
        "Could you place {A} behind {T}?",
    ),
    # ------------------------------------------------------------------ add a static object
    "cones_in_lane": (
        "Place {R} in our lane {d} ahead.",
        "Put {R} in the ego lane {d} ahead.",
        "drop {R} in my lane about {d} in front of us",
    ),
    "obstacle_in_lane": (
        "Put {A} in our lane {d} ahead.",
        "Place {A} in the ego lane about {d} in front of us.",
        "Drop {A} {d} ahead in my lane.",
    ),
    "cones_side_lane": (
        "Place {R} in the {side} lane {d} ahead.",
        "Put {R} {d} ahead in the lane to our {side}.",
    ),
    "static_on_road": (
        "Drop {A} on the road {d} ahead.",
        "Put {A} on the street about {d} in front of us.",
    ),
    "static_by_vehicle": (
        "Place {A} in front of {T}.",
        "Put {A} behind {T}.",
    ),
    # ------------------------------------------------------------------ add a pedestrian
    "jaywalker": (
        "Add {P} who jaywalks across the road {d} ahead of us.",
        "Insert {P} jaywalking across the street {d} in front of us.",
        "Spawn {P} crossing the road {d} ahead, away from any crosswalk.",
    ),
    "runner": (
        "Spawn {P} running across the street {d} in front of us.",
        "Add {P} who sprints across the road {d} ahead.",
    ),
    "crosswalk_walker": (
        "Put {P} on the crosswalk ahead crossing the road.",
        "Add {P} crossing at the crosswalk ahead.",
    ),
    "sidewalk_walker": (
        "Add {P} walking on the sidewalk {d} ahead.",
        "Put {P} on the sidewalk about {d} in front of us.",
    ),
    # ------------------------------------------------------------------ modify a vehicle
    "pull_out": (
        "Make {T} pull out.",
        "Have {T} pull away from the curb.",
    ),
    "replace": (
        "Replace {T} with {A}.",
        "Swap {T} for {A}.",
        "Turn {T} into {A}.",
    ),
    # ------------------------------------------------------------------ remove
    "remove": (
        "Remove {T}.",
        "Get rid of {T}.",
        "Delete {T}.",
        "Take out {T}.",
        "Erase {T} from the scene.",
    ),
    "remove_group": (
        "Remove {G}.",
        "Get rid of {G}.",
        "Delete {G}.",
    ),
    # ------------------------------------------------------------------ the behaviours' own (``editing.behaviours``)
    **PROPOSAL_FORMS,
}


def realise(kind: str, rng: np.random.Generator, **slots: str) -> str:
    """One of ``kind``'s sentence forms with ``slots`` filled in; a sentence starting with a slot is capitalised
    unless the form is colloquial (all lower case)."""
    form = pick(rng, FORMS[kind])
    text = form.format(**slots)
    return text if form[:1].islower() else capitalised(text)


__all__ = [
    "CONTEXT_PHRASES",
    "FORMS",
    "MOTION_AFTER",
    "MOTION_BEFORE",
    "SECTOR_PHRASES",
    "asset_phrase",
    "capitalised",
    "distance_phrase",
    "duration_phrase",
    "group_phrase",
    "lookalikes",
    "pick",
    "plural",
    "qualifiers_for",
    "realise",
    "referring_phrase",
    "row_phrase",
    "speed_phrase",
]
