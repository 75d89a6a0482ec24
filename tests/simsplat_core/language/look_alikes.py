"""A hand-built scene of look-alikes for the ``QueryEngine`` tests: objects that differ in one signal only.

    scene = hand_built_scene(SPECS, encoder, codebooks)
    scene.node(ID["A"])             # the red sedan turning left at the intersection
"""

from __future__ import annotations

from tests.simsplat_core.language.language_scene_factory import (
    ObjectSpec,
    motion_label,
    pedestrian_caption,
    vehicle_caption,
)

# node ids follow the spec order (1-based)
SPECS = [
    # three red sedans: A and B differ in motion only, A and C in location only; D is A in blue
    ObjectSpec("A", "vehicle", vehicle_caption("red", "sedan"),
               motion_label("A", "turning_left", "in_front_of_ego", "at_the_intersection")),
    ObjectSpec("B", "vehicle", vehicle_caption("red", "sedan"),
               motion_label("B", "going_straight", "in_front_of_ego", "at_the_intersection")),
    ObjectSpec("C", "vehicle", vehicle_caption("red", "sedan"),
               motion_label("C", "turning_left", "left_of_ego", "on_the_road")),
    ObjectSpec("D", "vehicle", vehicle_caption("blue", "sedan"),
               motion_label("D", "turning_left", "in_front_of_ego", "at_the_intersection")),
    # two parked white SUVs and a stopped white van
    ObjectSpec("E", "vehicle", vehicle_caption("white", "SUV"),
               motion_label("E", "parked", "right_of_ego", "by_the_curb")),
    ObjectSpec("F", "vehicle", vehicle_caption("white", "SUV"),
               motion_label("F", "parked", "behind_ego", "by_the_curb")),
    ObjectSpec("G", "vehicle", vehicle_caption("white", "van"),
               motion_label("G", "stopped", "in_front_of_ego", "on_the_road")),
    # pedestrians: P1/P2 dress alike (crossing vs standing); P3/P4 swap top and trousers colours
    ObjectSpec("P1", "pedestrian", pedestrian_caption("white", "gray"),
               motion_label("P1", "crossing_left_to_right", "in_front_of_ego", "on_the_crosswalk")),
    ObjectSpec("P2", "pedestrian", pedestrian_caption("white", "gray"),
               motion_label("P2", "standing", "in_front_of_ego", "on_the_sidewalk")),
    ObjectSpec("P3", "pedestrian", pedestrian_caption("blue", "red"),
               motion_label("P3", "walking_along", "left_of_ego", "on_the_sidewalk")),
    ObjectSpec("P4", "pedestrian", pedestrian_caption("red", "blue"),
               motion_label("P4", "walking_along", "right_of_ego", "on_the_sidewalk")),
    # street furniture: no motion features
    ObjectSpec("cone", "static", vehicle_caption("orange", "traffic cone", "static")),
]
ID = {spec.object_id: k + 1 for k, spec in enumerate(SPECS)}


def ids(*names: str) -> tuple[int, ...]:
    """Node ids of the named specs, in order."""
    return tuple(ID[n] for n in names)
