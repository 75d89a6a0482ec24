"""The behaviour vocabulary, spelled once: motion classes per agent kind, location sectors and map contexts.

The modules that name a class (auto-labeller, query parser and lexicon, scoring, paraphrases,
benchmarks) import the constants below (``TURNING_LEFT``, ``PARKED``, ``LEFT_OF_EGO``, ...) or look
classes up in the vocabularies; ``tests/simsplat_core/scenario/test_vocabulary.py`` fails when another
module spells a class name. The world's captions and behaviour names are English of their own (a
caption says "parked" as a word, not as a class) and are listed there as exempt.

Every class has a stable name (used in labels, persisted states and tables), several *prototype*
phrasings (encoded as E5 passages and averaged into the class prototype) and several *query*
phrasings (free-form descriptions a user might type; used only to evaluate grounding, so they are
deliberately worded differently from the prototypes).

Codebooks:

* ``VEHICLE_MOTION`` -- vehicles, cyclists and other movable objects.
* ``PEDESTRIAN_MOTION`` -- pedestrians.
* ``LOCATION_SECTOR`` -- where the object is relative to the ego (45-degree sectors).
* ``LOCATION_CONTEXT`` -- where the object is on the map.

The location codebook of the aligner is ``LOCATION_SECTOR + LOCATION_CONTEXT``: every object has
exactly one sector and one context label.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Agent kinds with a motion vocabulary (``trajectory.agent_kind`` maps object categories to them).
VEHICLE = "vehicle"
PEDESTRIAN = "pedestrian"

# Vehicle motion classes (also cyclists and other movers).
TURNING_LEFT = "turning_left"
TURNING_RIGHT = "turning_right"
GOING_STRAIGHT = "going_straight"
CHANGING_LANE_LEFT = "changing_lane_left"
CHANGING_LANE_RIGHT = "changing_lane_right"
SLOWING_DOWN = "slowing_down"
SPEEDING_UP = "speeding_up"
STOPPING = "stopping"
STOPPED = "stopped"
PARKED = "parked"
REVERSING = "reversing"

# Pedestrian motion classes.
CROSSING_LEFT_TO_RIGHT = "crossing_left_to_right"
CROSSING_RIGHT_TO_LEFT = "crossing_right_to_left"
CROSSING = "crossing"
WALKING_ALONG = "walking_along"
STANDING = "standing"

# Sectors around the ego.
IN_FRONT_OF_EGO = "in_front_of_ego"
BEHIND_EGO = "behind_ego"
LEFT_OF_EGO = "left_of_ego"
RIGHT_OF_EGO = "right_of_ego"

# Map contexts.
AT_THE_INTERSECTION = "at_the_intersection"
ON_THE_CROSSWALK = "on_the_crosswalk"
ON_THE_SIDEWALK = "on_the_sidewalk"
BY_THE_CURB = "by_the_curb"
IN_THE_ONCOMING_LANE = "in_the_oncoming_lane"
ON_THE_ROAD = "on_the_road"


@dataclass(frozen=True)
class PhraseClass:
    """One class of a codebook.

    Attributes:
        name: stable identifier, e.g. ``"turning_left"``.
        prototypes: phrasings averaged into the prototype (E5 passages).
        queries: differently worded free-form descriptions (E5 queries), for evaluation: whole
            descriptions for motion classes ("the car that turns left"), predicates for location
            classes ("ahead of me"), to be put after a subject ("the car ahead of me").
    """

    name: str
    prototypes: tuple[str, ...]
    queries: tuple[str, ...]


@dataclass(frozen=True)
class Vocabulary:
    """An ordered set of classes; the order is the codebook's prototype order."""

    name: str
    classes: tuple[PhraseClass, ...]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.classes)

    def index(self, name: str) -> int:
        return self.names.index(name)

    def __getitem__(self, name: str) -> PhraseClass:
        return self.classes[self.index(name)]

    def __len__(self) -> int:
        return len(self.classes)


VEHICLE_MOTION = Vocabulary(
    "vehicle_motion",
    (
        PhraseClass(
            TURNING_LEFT,
            ("a car turning left", "a vehicle making a left turn", "a car taking a left turn at the junction"),
            ("the car that turns left", "vehicle doing a left turn", "the car turning to the left"),
        ),
        PhraseClass(
            TURNING_RIGHT,
            ("a car turning right", "a vehicle making a right turn", "a car taking a right turn at the junction"),
            ("the car that turns right", "vehicle doing a right turn", "the car turning to the right"),
        ),
        PhraseClass(
            GOING_STRAIGHT,
            ("a car going straight", "a vehicle driving straight ahead", "a car moving forward along its lane"),
            ("the car driving straight", "vehicle continuing straight on", "the car cruising down the road"),
        ),
        PhraseClass(
            CHANGING_LANE_LEFT,
            ("a car changing lanes to the left", "a vehicle moving into the left lane", "a car merging left"),
            (
                "the car switching to the left lane",
                "vehicle doing a lane change to the left",
                "the car cutting left into the next lane",
            ),
        ),
        PhraseClass(
            CHANGING_LANE_RIGHT,
            ("a car changing lanes to the right", "a vehicle moving into the right lane", "a car merging right"),
            (
                "the car switching to the right lane",
                "vehicle doing a lane change to the right",
                "the car cutting right into the next lane",
            ),
        ),
        PhraseClass(
            SLOWING_DOWN,
            ("a car slowing down", "a vehicle decelerating", "a car braking and reducing its speed"),
            ("the car that is slowing", "vehicle hitting the brakes", "the car losing speed"),
        ),
        PhraseClass(
            SPEEDING_UP,
            ("a car speeding up", "a vehicle accelerating", "a car pulling away and gaining speed"),
            ("the car that is accelerating", "vehicle picking up speed", "the car starting to move off"),
        ),
        PhraseClass(
            STOPPING,
            ("a car coming to a stop", "a vehicle braking to a halt", "a car pulling up and stopping"),
            ("the car that stops", "vehicle coming to a halt", "the car braking until it stands still"),
        ),
        PhraseClass(
            STOPPED,
            (
                "a stopped car waiting in its lane",
                "a vehicle standing still in traffic",
                "a car waiting at the stop line",
            ),
            ("the car that is waiting", "vehicle stopped in the lane", "the stationary car queuing in traffic"),
        ),
        PhraseClass(
            PARKED,
            ("a parked car", "a vehicle parked at the curb", "a car parked by the side of the road"),
            ("the parked vehicle", "car parked along the street", "the car sitting in a parking spot"),
        ),
        PhraseClass(
            REVERSING,
            ("a car reversing", "a vehicle backing up", "a car driving backwards"),
            ("the car that is backing up", "vehicle in reverse gear", "the car moving in reverse"),
        ),
    ),
)

PEDESTRIAN_MOTION = Vocabulary(
    "pedestrian_motion",
    (
        PhraseClass(
            CROSSING_LEFT_TO_RIGHT,
            (
                "a pedestrian crossing the street from left to right",
                "a person walking across the road from the left to the right",
                "a pedestrian crossing in front from left to right",
            ),
            (
                "the person crossing from left to right",
                "pedestrian walking across the road left to right",
                "someone crossing over to the right side",
            ),
        ),
        PhraseClass(
            CROSSING_RIGHT_TO_LEFT,
            (
                "a pedestrian crossing the street from right to left",
                "a person walking across the road from the right to the left",
                "a pedestrian crossing in front from right to left",
            ),
            (
                "the person crossing from right to left",
                "pedestrian walking across the road right to left",
                "someone crossing over to the left side",
            ),
        ),
        PhraseClass(
            CROSSING,
            (
                "a pedestrian crossing the street",
                "a person walking across the road",
                "a pedestrian on the way across the street",
            ),
            ("the person crossing the road", "pedestrian going across the street", "someone crossing"),
        ),
        PhraseClass(
            WALKING_ALONG,
            (
                "a pedestrian walking along the sidewalk",
                "a person walking along the street",
                "a pedestrian strolling on the pavement",
            ),
            ("the person walking down the sidewalk", "pedestrian walking beside the road", "someone strolling along"),
        ),
        PhraseClass(
            STANDING,
            ("a pedestrian standing still", "a person standing and waiting", "a pedestrian who is not moving"),
            ("the person standing there", "pedestrian waiting without moving", "someone standing still"),
        ),
    ),
)

LOCATION_SECTOR = Vocabulary(
    "location_sector",
    (
        PhraseClass(
            IN_FRONT_OF_EGO,
            ("in front of the ego vehicle", "ahead of us", "directly ahead of the ego car"),
            ("ahead of me", "in front of our car", "right ahead of us"),
        ),
        PhraseClass(
            BEHIND_EGO,
            ("behind the ego vehicle", "behind us", "to the rear of the ego car"),
            ("behind me", "at the back of our car", "following behind us"),
        ),
        PhraseClass(
            LEFT_OF_EGO,
            ("on the left of the ego vehicle", "to our left", "on the left side of the ego car"),
            ("on my left", "on the left-hand side", "to the left of our car"),
        ),
        PhraseClass(
            RIGHT_OF_EGO,
            ("on the right of the ego vehicle", "to our right", "on the right side of the ego car"),
            ("on my right", "on the right-hand side", "to the right of our car"),
        ),
    ),
)

LOCATION_CONTEXT = Vocabulary(
    "location_context",
    (
        PhraseClass(
            AT_THE_INTERSECTION,
            ("at the intersection", "in the middle of the junction", "inside the crossroads"),
            ("in the intersection", "within the junction", "at the crossroads"),
        ),
        PhraseClass(
            ON_THE_CROSSWALK,
            ("on the crosswalk", "on the zebra crossing", "on the pedestrian crossing"),
            ("on the zebra", "crossing at the crosswalk", "on the pedestrian crossing"),
        ),
        PhraseClass(
            ON_THE_SIDEWALK,
            ("on the sidewalk", "on the pavement", "on the footpath beside the road"),
            ("on the pavement", "up on the sidewalk", "on the footpath"),
        ),
        PhraseClass(
            BY_THE_CURB,
            ("by the curb", "at the side of the road", "in the parking lane"),
            ("next to the curb", "at the roadside", "in the parking strip"),
        ),
        PhraseClass(
            IN_THE_ONCOMING_LANE,
            ("in the oncoming lane", "oncoming traffic", "approaching from the opposite direction"),
            ("oncoming", "driving towards us", "in the opposite direction lane"),
        ),
        PhraseClass(
            ON_THE_ROAD,
            ("on the road", "in a travel lane", "on the street"),
            ("on the street", "in the lane", "out on the road"),
        ),
    ),
)

MOTION_VOCABULARIES: dict[str, Vocabulary] = {VEHICLE: VEHICLE_MOTION, PEDESTRIAN: PEDESTRIAN_MOTION}

#: Every motion class name of any agent kind, in vocabulary order.
MOTION_CLASSES: tuple[str, ...] = VEHICLE_MOTION.names + PEDESTRIAN_MOTION.names
#: The location classes (the aligner's location codebook): sectors, then map contexts.
LOCATION_CLASSES: tuple[str, ...] = LOCATION_SECTOR.names + LOCATION_CONTEXT.names

#: One-word nouns that name an intersection (the ``AT_THE_INTERSECTION`` map context); the query lexicon and
#: the edit parser read these.
INTERSECTION_NOUNS: tuple[str, ...] = ("intersection", "intersections", "junction", "junctions", "crossroads",
                                       "crossroad")
#: :data:`INTERSECTION_NOUNS` as a regex alternation (no group), longest first so a word matches whole.
INTERSECTION_RX = "|".join(sorted(INTERSECTION_NOUNS, key=len, reverse=True))
