"""Words of the editing prompt set: sentence forms per intent, and the phrases that fill them.

Every intent kind (``FORMS``) has several sentence forms written for this benchmark -- imperative,
declarative, polite, colloquial, with synonyms ("add" / "put" / "insert" / "spawn" / "drop", "remove" /
"delete" / "get rid of") -- whose slots are filled with phrases drawn from small synonym tables:

* ``{T}`` / ``{anchor}``: a definite description of a scene object (built from ground truth by
  ``prompts.py`` with the grounding benchmark's paraphraser, so it singles the object out);
* ``{A}``: an indefinite asset description ("a red SUV", "a person in a yellow jacket", "an orange cone");
* ``{d}``: a distance ("20 m", "20 meters", "20 metres"); ``{v}``: a speed in km/h, m/s or mph;
  ``{t}``: a duration; ``{side}``: "left" / "right"; ``{n}`` / ``{items}``: a count and a plural noun.

Speeds are rounded to what a person would say in the chosen unit ("30 km/h", "8 m/s", "20 mph"); the
exact value in m/s of the words is what the prompt's intent records.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.editing.behaviours.registry import PROMPT_FORMS
from simsplat_core.editing.commands import SPEED_UNITS
from simsplat_core.language.appearance.captioner import article

#: Sentence forms per intent kind (see the module docstring for the slots).
FORMS: dict[str, tuple[str, ...]] = {
    # ------------------------------------------------------------------ add a vehicle
    "vehicle_lane_ahead": (
        "Add {A} {d} ahead of us in our lane.",
        "Put {A} in the ego lane, about {d} in front.",
        "Insert {A} {d} ahead in my lane.",
        "Place {A} in our lane {d} ahead of the ego car.",
        "spawn {A} {d} in front of us, same lane",
        "I want {A} in my lane roughly {d} ahead.",
        "Can you add {A} in the lane we're in, {d} up ahead?",
    ),
    "vehicle_side_lane": (
        "Add {A} in the {side} lane {d} ahead.",
        "Put {A} in the lane to our {side}, {d} ahead of us.",
        "Insert {A} one lane over to the {side}, about {d} in front.",
        "Place {A} {d} ahead in the {side}-hand lane.",
    ),
    "vehicle_oncoming": (
        "Add {A} in the oncoming lane {d} ahead.",
        "Put {A} in the opposite lane about {d} in front of us.",
        "Insert {A} {d} ahead in the lane of oncoming traffic.",
    ),
    "vehicle_behind_anchor": (
        "Add {A} behind {anchor}.",
        "Put {A} {d} behind {anchor}.",
        "Insert {A} right behind {anchor}.",
        "spawn {A} {d} behind {anchor}",
        "Could you place {A} behind {anchor}?",
    ),
    "vehicle_front_anchor": (
        "Add {A} {d} in front of {anchor}.",
        "Put {A} ahead of {anchor}.",
        "Place {A} directly in front of {anchor}.",
        "Insert {A} {d} ahead of {anchor}.",
    ),
    "vehicle_lane_speed": (
        "Add {A} {d} ahead in our lane driving at {v}.",
        "Insert {A} in the ego lane {d} ahead, going {v}.",
        "Put {A} {d} in front of us in my lane, moving at {v}.",
        "Spawn {A} {d} ahead in our lane travelling at {v}.",
    ),
    # ------------------------------------------------------------------ add a static object
    "static_lane_ahead": (
        "Place {A} in our lane {d} ahead.",
        "Put {A} in the ego lane {d} in front of us.",
        "Drop {A} {d} ahead in my lane.",
        "Add {A} in our lane about {d} ahead.",
    ),
    "static_side_lane": (
        "Put {A} in the {side} lane {d} ahead.",
        "Place {A} in the lane to our {side}, {d} up the road.",
        "Add {A} {d} ahead in the {side}-hand lane.",
    ),
    "static_row": (
        "Line up {n} {items} in our lane {d} ahead.",
        "Add {n} {items} in a row in our lane, {d} in front of us.",
        "Put a row of {n} {items} in the ego lane {d} ahead.",
    ),
    "static_row_side": (
        "Put a row of {n} {items} in the {side} lane {d} ahead.",
        "Place a line of {n} {items} in the lane to our {side}, about {d} ahead.",
        "Line up {n} {items} {d} ahead in the {side}-hand lane.",
    ),
    "static_anchor_behind": (
        "Drop {A} {d} behind {anchor}.",
        "Put {A} right behind {anchor}.",
        "Place {A} behind {anchor}.",
    ),
    "static_anchor_front": (
        "Put {A} in front of {anchor}.",
        "Place {A} {d} ahead of {anchor}.",
        "Add {A} just in front of {anchor}.",
    ),
    "static_anchor_side": (
        "Add {A} {d} to the {side} of {anchor}.",
        "Put {A} on the {side} side of {anchor}.",
        "Place {A} {d} {side} of {anchor}.",
    ),
    "static_sidewalk": (
        "Put {A} on the sidewalk {d} ahead.",
        "Place {A} on the pavement about {d} in front of us.",
        "Add {A} on the sidewalk roughly {d} ahead of the ego car.",
    ),
    "static_crosswalk": (
        "Put {A} on the crosswalk ahead.",
        "Place {A} on the zebra crossing in front of us.",
        "Add {A} on the pedestrian crossing ahead.",
    ),
    # ------------------------------------------------------------------ add a pedestrian
    "pedestrian_sidewalk": (
        "Add {A} on the sidewalk {d} ahead.",
        "Put {A} on the pavement about {d} in front of us.",
        "Place {A} standing on the sidewalk {d} ahead.",
        "Insert {A} on the footpath {d} ahead of the ego car.",
    ),
    "pedestrian_crosswalk": (
        "Add {A} on the crosswalk ahead.",
        "Put {A} on the zebra crossing in front of us.",
        "Place {A} on the pedestrian crossing ahead of us.",
    ),
    "pedestrian_crossing": (
        "Add {A} crossing the street {d} ahead.",
        "Have {A} walk across the road {d} in front of us.",
        "Insert {A} who crosses the street {d} ahead.",
        "Put {A} {d} ahead, walking across the road.",
    ),
    "pedestrian_insert_jaywalk": (
        "Add {A} jaywalking across the road {d} ahead.",
        "Insert {A} crossing the street away from the crosswalk, {d} ahead.",
        "Have {A} jaywalk across the street {d} in front of us.",
    ),
    "pedestrian_next_to": (
        "Add {A} next to {anchor}.",
        "Put {A} beside {anchor}.",
        "Insert {A} standing next to {anchor}.",
    ),
    "pedestrian_side_of": (
        "Place {A} {d} to the {side} of {anchor}.",
        "Put {A} on the {side} side of {anchor}.",
        "Add {A} {d} {side} of {anchor}.",
    ),
    "pedestrian_walk_speed": (
        "Add {A} walking along the sidewalk {d} ahead at {v}.",
        "Put {A} on the pavement {d} ahead, walking at {v}.",
        "Insert {A} strolling along the sidewalk {d} in front of us at {v}.",
    ),
    "pedestrian_insert_run": (
        "Add {A} running along the sidewalk {d} ahead.",
        "Put {A} jogging on the pavement {d} in front of us.",
        "Insert {A} who runs along the sidewalk {d} ahead.",
    ),
    # ------------------------------------------------------------------ modify a vehicle
    "vehicle_replace": (
        "Replace {T} with {A}.",
        "Swap {T} for {A}.",
        "Turn {T} into {A}.",
    ),
    # ------------------------------------------------------------------ remove
    "remove_single": (
        "Remove {T}.",
        "Delete {T}.",
        "Get rid of {T}.",
        "Erase {T} from the scene.",
        "Take {T} out of the scene.",
        "Please remove {T}.",
    ),
    "remove_static": (
        "Remove {T}.",
        "Take away {T}.",
        "Get rid of {T} next to the road.",
        "Delete {T} from the street.",
    ),
    "remove_group": (
        "Remove {T}.",
        "Delete {T}.",
        "Get rid of {T}.",
        "Clear {T} from the scene.",
    ),
    # ------------------------------------------------------------------ infeasible
    "absent_remove": ("Remove {T}.", "Delete {T} from the scene."),
    "absent_modify": ("Make {T} stop.", "{T} should turn left at the intersection."),
    "absent_anchor": ("Add {A} behind {anchor}.", "Put {A} next to {anchor}."),
    "car_on_sidewalk": (
        "Put {A} on the sidewalk {d} ahead.",
        "Park {A} on the pavement {d} in front of us.",
        "Add {A} on the sidewalk next to the road.",
    ),
    "static_motion": (
        "Make {T} drive at {v}.",
        "{T} should move at {v}.",
        "Have {T} roll down the road at {v}.",
    ),
    "nonsense": (
        "Make the sky purple.",
        "Paint the road blue.",
        "asdf qwerty zxcv",
        "Turn the traffic light green.",
        "Play some music.",
        "Make it rain.",
        "What time is it?",
        "Make the buildings taller.",
    ),
    # ------------------------------------------------------------------ the behaviours' own (``editing.behaviours``)
    **PROMPT_FORMS,
}

_DISTANCE_UNITS = ("{x} m", "{x} meters", "{x} metres", "{x}m")
_SPEED_WORDS: dict[str, tuple[str, ...]] = {
    "km/h": ("{x} km/h", "{x} kph", "{x} kilometers per hour", "{x} km per hour"),
    "m/s": ("{x} m/s", "{x} meters per second", "{x} metres per second"),
    "mph": ("{x} mph", "{x} miles per hour"),
}
_SECONDS = ("{x} seconds", "{x} s", "{x} secs")
_NUMBERS = {2: "two", 3: "three", 4: "four", 5: "five", 6: "six"}


def pick(rng: np.random.Generator, options: tuple[str, ...] | list[str]) -> str:
    return options[int(rng.integers(len(options)))]


def _number(x: float) -> str:
    return f"{x:g}"


def _singular(text: str) -> str:
    """``"1 meters"`` -> ``"1 meter"`` (and metres, seconds, secs, miles)."""
    for plural, single in (("meters", "meter"), ("metres", "metre"), ("seconds", "second"), ("secs", "sec"),
                           ("miles", "mile")):
        if text.startswith("1 ") and plural in text:
            return text.replace(plural, single, 1)
    return text


def distance_phrase(metres: float, rng: np.random.Generator) -> str:
    """``"20 m"`` / ``"20 meters"`` / ... (``metres`` is said as given, rounded to 0.5 m)."""
    return _singular(pick(rng, _DISTANCE_UNITS).format(x=_number(round(metres * 2) / 2)))


def seconds_phrase(seconds: float, rng: np.random.Generator) -> str:
    return _singular(pick(rng, _SECONDS).format(x=_number(seconds)))


def speed_words(target_mps: float, unit: str, rng: np.random.Generator) -> tuple[str, float, float]:
    """``(phrase, value said, m/s of the value said)``: ``target_mps`` rounded to what one says in ``unit``
    (km/h and mph to 5, m/s to 0.5 below 3 m/s, else to 1)."""
    per = SPEED_UNITS[unit]
    raw = target_mps / per
    if unit == "m/s":
        value = round(raw * 2) / 2 if raw < 3 else float(round(raw))
    else:
        value = float(max(5, 5 * round(raw / 5)))
    return _singular(pick(rng, _SPEED_WORDS[unit]).format(x=_number(value))), value, value * per


def count_word(n: int, rng: np.random.Generator) -> str:
    return _NUMBERS.get(n, str(n)) if rng.random() < 0.6 else str(n)


def indefinite(noun_phrase: str) -> str:
    return f"{article(noun_phrase)} {noun_phrase}"


#: Relative speed phrases: ``(words, mode, value, unit)`` as ``commands.SpeedSpec`` reads them.
VEHICLE_RELATIVE_SPEEDS: tuple[tuple[str, str, float, str], ...] = (
    ("twice as fast", "factor", 2.0, "m/s"),
    ("half as fast", "factor", 0.5, "m/s"),
    ("50% faster", "factor", 1.5, "m/s"),
    ("10 km/h faster", "delta", 10.0, "km/h"),
    ("10 km/h slower", "delta", -10.0, "km/h"),
    ("5 mph slower", "delta", -5.0, "mph"),
    ("3 m/s faster", "delta", 3.0, "m/s"),
)
PEDESTRIAN_RELATIVE_SPEEDS: tuple[tuple[str, str, float, str], ...] = (
    ("twice as fast", "factor", 2.0, "m/s"),
    ("half as fast", "factor", 0.5, "m/s"),
    ("50% faster", "factor", 1.5, "m/s"),
    ("more slowly, at half the speed", "factor", 0.5, "m/s"),
)

#: Words of inserted pedestrians: nouns and garments.
PERSON_NOUNS = ("pedestrian", "person", "man", "woman", "pedestrian", "person")
TOP_NOUNS = ("jacket", "shirt", "top", "coat", "hoodie", "sweater")
BOTTOM_NOUNS = ("pants", "trousers", "jeans")


def person_phrase(upper: str | None, lower: str | None, rng: np.random.Generator) -> str:
    """``"a person in a red jacket"`` / ``"a woman wearing a blue top and black pants"`` (indefinite)."""
    noun = pick(rng, PERSON_NOUNS)
    parts = []
    if upper is not None:
        parts.append(indefinite(f"{upper} {pick(rng, TOP_NOUNS)}"))
    if lower is not None:
        parts.append(f"{lower} {pick(rng, BOTTOM_NOUNS)}")
    if not parts:
        return indefinite(noun)
    return f"{indefinite(noun)} {pick(rng, ('in', 'wearing'))} {' and '.join(parts)}"


__all__ = ["FORMS", "PEDESTRIAN_RELATIVE_SPEEDS", "VEHICLE_RELATIVE_SPEEDS", "count_word", "distance_phrase",
           "indefinite", "person_phrase", "pick", "seconds_phrase", "speed_words"]
