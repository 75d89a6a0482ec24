"""A hand-built scene of look-alikes for the ``QueryEngine`` tests: objects that differ in one signal only.

    scene = hand_built_scene(SPECS, encoder, codebooks)
    scene.node(ID["A"])             # the red sedan turning left at the intersection
"""

from __future__ import annotations

from simsplat_core.scenario import vocabulary as voc
from tests.simsplat_core.language.language_scene_factory import (
    ObjectSpec,
    motion_label,
    pedestrian_caption,
    vehicle_caption,
)

# node ids follow the spec order (1-based)
SPECS = [
    # three red sedans: A and B differ in motion only, A and C in location only; D is A in blue
    ObjectSpec(
        "A",
        "vehicle",
        vehicle_caption("red", "sedan"),
        motion_label("A", voc.TURNING_LEFT, voc.IN_FRONT_OF_EGO, voc.AT_THE_INTERSECTION),
    ),
    ObjectSpec(
        "B",
        "vehicle",
        vehicle_caption("red", "sedan"),
        motion_label("B", voc.GOING_STRAIGHT, voc.IN_FRONT_OF_EGO, voc.AT_THE_INTERSECTION),
    ),
    ObjectSpec(
        "C",
        "vehicle",
        vehicle_caption("red", "sedan"),
        motion_label("C", voc.TURNING_LEFT, voc.LEFT_OF_EGO, voc.ON_THE_ROAD),
    ),
    ObjectSpec(
        "D",
        "vehicle",
        vehicle_caption("blue", "sedan"),
        motion_label("D", voc.TURNING_LEFT, voc.IN_FRONT_OF_EGO, voc.AT_THE_INTERSECTION),
    ),
    # two parked white SUVs and a stopped white van
    ObjectSpec(
        "E",
        "vehicle",
        vehicle_caption("white", "SUV"),
        motion_label("E", voc.PARKED, voc.RIGHT_OF_EGO, voc.BY_THE_CURB),
    ),
    ObjectSpec(
        "F", "vehicle", vehicle_caption("white", "SUV"), motion_label("F", voc.PARKED, voc.BEHIND_EGO, voc.BY_THE_CURB)
    ),
    ObjectSpec(
        "G",
        "vehicle",
        vehicle_caption("white", "van"),
        motion_label("G", voc.STOPPED, voc.IN_FRONT_OF_EGO, voc.ON_THE_ROAD),
    ),
    # pedestrians: P1/P2 dress alike (crossing vs standing); P3/P4 swap top and trousers colours
    ObjectSpec(
        "P1",
        "pedestrian",
        pedestrian_caption("white", "gray"),
        motion_label("P1", voc.CROSSING_LEFT_TO_RIGHT, voc.IN_FRONT_OF_EGO, voc.ON_THE_CROSSWALK),
    ),
    ObjectSpec(
        "P2",
        "pedestrian",
        pedestrian_caption("white", "gray"),
        motion_label("P2", voc.STANDING, voc.IN_FRONT_OF_EGO, voc.ON_THE_SIDEWALK),
    ),
    ObjectSpec(
        "P3",
        "pedestrian",
        pedestrian_caption("blue", "red"),
        motion_label("P3", voc.WALKING_ALONG, voc.LEFT_OF_EGO, voc.ON_THE_SIDEWALK),
    ),
    ObjectSpec(
        "P4",
        "pedestrian",
        pedestrian_caption("red", "blue"),
        motion_label("P4", voc.WALKING_ALONG, voc.RIGHT_OF_EGO, voc.ON_THE_SIDEWALK),
    ),
    # street furniture: no motion features
    ObjectSpec("cone", "static", vehicle_caption("orange", "traffic cone", "static")),
]
ID = {spec.object_id: k + 1 for k, spec in enumerate(SPECS)}


def ids(*names: str) -> tuple[int, ...]:
    """Node ids of the named specs, in order."""
    return tuple(ID[n] for n in names)
