"""Object subtypes from the category and the 3D box size ``(length, width, height)`` in metres.

A size rule is all a captioner can rely on for every source (a rendered Gaussian node has a box but
no class head). Thresholds, checked in order:

Vehicles (``category`` ``vehicle``, ``other``):

==================  =======================================================
``motorcycle``       length < 2.6 and width < 1.3
``bus``              length >= 9.5 and height >= 2.6
``truck``            length >= 6.5 or height >= 2.6
``van``              height >= 1.98
``pickup truck``     length >= 5.15
``SUV``              height >= 1.6
``hatchback``        length < 4.3
``sedan``            otherwise
==================  =======================================================

The boundaries sit midway between typical passenger-car dimensions: a sedan is ~4.6 x 1.8 x 1.45 m,
a hatchback ~4.05 m long, an SUV ~4.85 x 1.95 x 1.78 m, a pickup ~5.5 x 2.0 x 1.85 m, a van
~5.2 x 2.0 x 2.1 m, a box truck ~7.6 x 2.45 x 3.3 m, a city bus ~11.5 x 2.55 x 3.15 m (these are the
synthetic world's catalogue values, which follow common real models). Cyclists are a ``bicycle``,
or a ``motorcycle`` when longer than 2.1 m.

Pedestrians: ``child`` below ``CHILD_HEIGHT`` (1.3 m), else ``adult``.

Static objects: ``traffic cone`` when the footprint is below 0.8 m and the height below 1.2 m,
``barrier`` when longer than 1.0 m and lower than 1.5 m, ``pole`` when thin and taller than 1.8 m,
else ``object``. Signs: ``sign``; ``refine_sign`` names the common kinds from the dominant colour
(US convention: red = stop sign, white = speed limit sign, blue = parking sign).
"""

from __future__ import annotations

import numpy as np

CHILD_HEIGHT = 1.3

VEHICLE_SUBTYPES: tuple[str, ...] = (
    "sedan",
    "hatchback",
    "SUV",
    "van",
    "pickup truck",
    "truck",
    "bus",
    "motorcycle",
)
PEDESTRIAN_SUBTYPES: tuple[str, ...] = ("adult", "child")
CYCLIST_SUBTYPES: tuple[str, ...] = ("bicycle", "motorcycle")
STATIC_SUBTYPES: tuple[str, ...] = ("traffic cone", "barrier", "pole", "object")
SIGN_SUBTYPES: tuple[str, ...] = ("stop sign", "speed limit sign", "parking sign", "sign")

_SIGN_BY_COLOR = {"red": "stop sign", "white": "speed limit sign", "blue": "parking sign"}


def vehicle_subtype(length: float, width: float, height: float) -> str:
    """Vehicle body style from its box (see the module table)."""
    if length < 2.6 and width < 1.3:
        return "motorcycle"
    if length >= 9.5 and height >= 2.6:
        return "bus"
    if length >= 6.5 or height >= 2.6:
        return "truck"
    if height >= 1.98:
        return "van"
    if length >= 5.15:
        return "pickup truck"
    if height >= 1.6:
        return "SUV"
    if length < 4.3:
        return "hatchback"
    return "sedan"


def static_subtype(length: float, width: float, height: float) -> str:
    """Street-furniture kind from its box (see the module docstring)."""
    footprint = max(length, width)
    if footprint < 0.8 and height < 1.2:
        return "traffic cone"
    if footprint > 1.0 and height < 1.5:
        return "barrier"
    if min(length, width) < 0.3 and height > 1.8:
        return "pole"
    return "object"


def subtype_from_size(category: str, box_size) -> str:
    """Subtype of an object of ``category`` with box ``[3]`` ``(length, width, height)`` metres."""
    length, width, height = (float(v) for v in np.asarray(box_size, dtype=np.float64).reshape(3))
    if category == "pedestrian":
        return "child" if height < CHILD_HEIGHT else "adult"
    if category == "cyclist":
        return "motorcycle" if length > 2.1 else "bicycle"
    if category in ("vehicle", "other"):
        return vehicle_subtype(length, width, height)
    if category == "sign":
        return "sign"
    if category == "static":
        return static_subtype(length, width, height)
    return "object"


def refine_sign(subtype: str, color: str) -> str:
    """A generic ``sign`` named from its colour (``SIGN_SUBTYPES``); other subtypes unchanged."""
    if subtype == "sign":
        return _SIGN_BY_COLOR.get(color, subtype)
    return subtype
