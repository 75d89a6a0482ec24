"""Size-based subtypes: the world's catalogue (with its +-3 % size jitter), people, street furniture."""

from __future__ import annotations

import pytest

from simsplat_core.language.appearance.subtypes import refine_sign, subtype_from_size
from simsplat_core.world.palette import STATIC_KINDS, VEHICLE_KINDS


@pytest.mark.parametrize("kind", VEHICLE_KINDS, ids=lambda k: k.subtype)
@pytest.mark.parametrize("jitter", [0.97, 1.0, 1.03])
def test_world_vehicle_catalogue(kind, jitter):
    length, width, height = kind.size
    size = (length * jitter, width * (1 + (jitter - 1) / 2), height * jitter)  # as agents.py jitters
    assert subtype_from_size("vehicle", size) == kind.subtype


@pytest.mark.parametrize(
    ("size", "expected"),
    [
        ((2.2, 0.8, 1.4), "motorcycle"),
        ((18.0, 2.55, 3.2), "bus"),
        ((6.0, 2.1, 2.7), "truck"),
        ((7.0, 2.3, 2.4), "truck"),
    ],
)
def test_other_vehicle_sizes(size, expected):
    assert subtype_from_size("vehicle", size) == expected


@pytest.mark.parametrize(("height", "expected"), [(1.1, "child"), (1.29, "child"), (1.55, "adult"), (1.92, "adult")])
def test_pedestrian_child_or_adult(height, expected):
    assert subtype_from_size("pedestrian", (0.5, 0.6, height)) == expected


def test_cyclist_subtypes():
    assert subtype_from_size("cyclist", (1.8, 0.6, 1.7)) == "bicycle"
    assert subtype_from_size("cyclist", (2.3, 0.9, 1.5)) == "motorcycle"


@pytest.mark.parametrize("subtype", ["traffic cone", "barrier"])
def test_world_static_catalogue(subtype):
    category, size, _ = STATIC_KINDS[subtype]
    assert subtype_from_size(category, size) == subtype


@pytest.mark.parametrize(
    ("subtype", "color"), [("stop sign", "red"), ("speed limit sign", "white"), ("parking sign", "blue")]
)
def test_world_signs_from_size_and_color(subtype, color):
    category, size, _ = STATIC_KINDS[subtype]
    assert refine_sign(subtype_from_size(category, size), color) == subtype


def test_refine_sign_leaves_other_subtypes_and_unknown_colors():
    assert refine_sign("barrier", "red") == "barrier"
    assert refine_sign("sign", "green") == "sign"
