"""The colours the procedural world paints with and its object catalogue.

Colour RGBs come from the one table of named colours, ``simsplat_core/color_names.py``.

The catalogue fixes what kinds of vehicles, clothing and street furniture exist, with their
dimensions; captions use the same names, so a colour word always matches the rendered colour.
"""

from __future__ import annotations

from dataclasses import dataclass

from simsplat_core.color_names import DISPLAY_RGB

#: Colours the world paints with, in this order (samplers index it); display RGB from the naming palette.
WORLD_COLOR_NAMES: tuple[str, ...] = (
    "black", "white", "silver", "gray", "red", "blue", "yellow", "green", "orange", "brown", "beige",
)
NAMED_COLORS: dict[str, tuple[float, float, float]] = {name: DISPLAY_RGB[name] for name in WORLD_COLOR_NAMES}


@dataclass(frozen=True)
class VehicleKind:
    """A vehicle subtype: nominal box ``(length, width, height)`` in metres and allowed colours."""

    subtype: str
    size: tuple[float, float, float]
    colors: tuple[str, ...]
    weight: float


VEHICLE_KINDS: tuple[VehicleKind, ...] = (
    VehicleKind("sedan", (4.6, 1.82, 1.45), ("black", "white", "silver", "gray", "red", "blue", "green"), 3.0),
    VehicleKind("hatchback", (4.05, 1.76, 1.5), ("white", "red", "blue", "yellow", "silver", "green"), 1.2),
    VehicleKind("SUV", (4.85, 1.95, 1.78), ("black", "white", "silver", "gray", "red", "blue"), 2.5),
    VehicleKind("van", (5.2, 2.0, 2.1), ("white", "silver", "gray", "blue"), 1.0),
    VehicleKind("pickup truck", (5.5, 2.0, 1.85), ("black", "white", "red", "blue", "gray"), 0.8),
    VehicleKind("truck", (7.6, 2.45, 3.3), ("white", "red", "blue", "yellow"), 0.5),
    VehicleKind("bus", (11.5, 2.55, 3.15), ("white", "yellow", "blue", "red"), 0.35),
)
VEHICLE_KIND_BY_NAME = {k.subtype: k for k in VEHICLE_KINDS}

#: Cars used for look-alike pairs (common, so a pair is unremarkable) and their colours.
LOOKALIKE_SUBTYPES: tuple[str, ...] = ("sedan", "SUV", "hatchback")
LOOKALIKE_COLORS: tuple[str, ...] = ("black", "white", "silver", "red", "blue")

UPPER_COLORS: tuple[str, ...] = ("red", "blue", "white", "black", "yellow", "green", "gray", "orange")
LOWER_COLORS: tuple[str, ...] = ("blue", "black", "gray", "beige", "brown")
SKIN_TONES: tuple[tuple[float, float, float], ...] = (
    (0.87, 0.7, 0.58),
    (0.72, 0.53, 0.4),
    (0.48, 0.33, 0.23),
    (0.3, 0.2, 0.14),
)
HAIR_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.08, 0.06, 0.05),
    (0.3, 0.2, 0.1),
    (0.6, 0.5, 0.3),
    (0.45, 0.45, 0.45),
)

#: Static street furniture: subtype -> (category, box size, colours).
STATIC_KINDS: dict[str, tuple[str, tuple[float, float, float], tuple[str, ...]]] = {
    "traffic cone": ("static", (0.42, 0.42, 0.72), ("orange",)),
    "barrier": ("static", (2.0, 0.55, 0.85), ("orange", "white", "gray")),
    "stop sign": ("sign", (0.12, 0.76, 2.6), ("red",)),
    "speed limit sign": ("sign", (0.12, 0.62, 2.5), ("white",)),
    "parking sign": ("sign", (0.12, 0.6, 2.45), ("blue",)),
}

BUILDING_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.72, 0.66, 0.56),
    (0.6, 0.36, 0.28),
    (0.55, 0.56, 0.58),
    (0.8, 0.78, 0.72),
    (0.45, 0.4, 0.36),
    (0.66, 0.58, 0.46),
)
LEAF_COLORS: tuple[tuple[float, float, float], ...] = ((0.16, 0.38, 0.14), (0.22, 0.42, 0.16), (0.13, 0.32, 0.18))


def article(word: str) -> str:
    """``"a"`` or ``"an"`` for the following word."""
    return "an" if word[:1].lower() in "aeiou" else "a"
