"""The query lexicon of the ``QueryEngine``: which words name which motion, location, colour and subtype.

* motion: ``MOTION_KEYWORDS`` (phrase regex -> the motion classes it names), the crossing classes that
  scoring merges (``CROSSING_CLASSES``), the classes of objects that do not move
  (``STATIONARY_CLASSES``) and the merged pedestrian classes (``PEDESTRIAN_MERGED``);
* location: ``SECTOR_KEYWORDS`` and ``CONTEXT_KEYWORDS`` (class -> phrase regex);
* appearance: colour names people use interchangeably (``SIMILAR_COLORS``) and the caption subtypes a
  named subtype also fits (``SUBTYPE_FIT``).

Class names are ``vocabulary.py``'s; ``scoring`` turns these tables into keyword priors and
attribute factors.
"""

from __future__ import annotations

from simsplat_core.scenario import vocabulary as voc

#: Pedestrian motion classes merged into one "crossing" for scoring (the direction is checked on its own).
CROSSING_CLASSES = (voc.CROSSING, voc.CROSSING_LEFT_TO_RIGHT, voc.CROSSING_RIGHT_TO_LEFT)
#: Motion classes of an object that does not move (the motion score of static objects and signs).
STATIONARY_CLASSES = (voc.PARKED, voc.STOPPED, voc.STANDING)

#: Keyword priors: motion phrase regex -> the classes it names (``vocabulary.py`` names, "crossing" =
#: any crossing); each query's prior is uniform over the named classes of the kinds it can refer to.
#: Words that say whose lane or street a phrase means ("in *their* lane"), as a regex alternation.
OWNER_WORDS = r"the|its|their|his|her"

MOTION_KEYWORDS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (r"\bleft\b.*\bturn|\bturn\w*\b.*\bleft\b|(?:hang|swing|veer|bear|tak)\w* (?:a )?left", (voc.TURNING_LEFT,)),
    (r"\bright\b.*\bturn|\bturn\w*\b.*\bright\b|(?:hang|swing|veer|bear|tak)\w* (?:a )?right", (voc.TURNING_RIGHT,)),
    # "corner" is a turn only as a verb or taken ("cornering", "round the corner"), not a place ("on the corner")
    (r"^(?!.*\b(?:left|right)\b).*(?:\bturn|\bcorner(?:ing|s)\b|(?:round|around|take|takes|taking|turning|turns)"
     r" (?:the |a )?corner)", (voc.TURNING_LEFT, voc.TURNING_RIGHT)),
    (r"straight|cruising|\bcontinu", (voc.GOING_STRAIGHT,)),
    (r"(?:lane|merg|switch|cut|shift|hop)\w*.*\bleft\b|\bleft\b.*\blane", (voc.CHANGING_LANE_LEFT,)),
    (r"(?:lane|merg|switch|cut|shift|hop)\w*.*\bright\b|\bright\b.*\blane", (voc.CHANGING_LANE_RIGHT,)),
    (r"\bslow|decelerat|\bbrak(?!\w* (?:to|until))|losing speed|reducing|easing off", (voc.SLOWING_DOWN,)),
    (
        r"speed\w* up|accelerat|picking up speed|gaining speed|pull\w* away|starting to move|moving off|on the gas",
        (voc.SPEEDING_UP,),
    ),
    (
        r"(?:coming|comes|pull\w*|brak\w*) (?:up )?to a (?:stop|halt|standstill)"
        r"|\bstopping\b|\bstops\b|pull\w* up|until it stands",
        (voc.STOPPING,),
    ),
    (
        r"stationary|not moving|not going anywhere|sitting still|motionless|standstill|standing still(?! in traffic)",
        (voc.STOPPED, voc.PARKED, voc.STANDING),
    ),
    (
        r"\bstopped\b|\bhalted\b|idling|queu|waiting|(?:standing still )?in traffic|\bstuck\b"
        rf"|(?:sitting )?in (?:{OWNER_WORDS}) lane",
        (voc.STOPPED, voc.STANDING),
    ),
    (r"\bparked\b|parking (?:spot|space|bay)", (voc.PARKED,)),
    (r"revers|\bback(?:ing|s)? (?:up|out)|backwards?", (voc.REVERSING,)),
    (r"cross|across|\bleft\b.*\bright\b|\bright\b.*\bleft\b|(?:to|towards) the (?:left|right)", (voc.CROSSING,)),
    (r"walk|stroll|\bjog|running|\bruns\b|wander|pacing", (voc.WALKING_ALONG,)),
    (r"\bstand|waiting|loiter|linger|\bstill\b", (voc.STANDING,)),
)
#: Merged motion classes by agent kind (what ``MOTION_KEYWORDS`` may name for each kind).
PEDESTRIAN_MERGED = (voc.CROSSING, voc.WALKING_ALONG, voc.STANDING)
SECTOR_KEYWORDS: tuple[tuple[str, str], ...] = (
    (voc.IN_FRONT_OF_EGO, r"front|ahead"),
    (voc.BEHIND_EGO, r"behind|\bback\b|\brear\b|following"),
    (voc.LEFT_OF_EGO, r"\bleft\b"),
    (voc.RIGHT_OF_EGO, r"\bright\b(?! (?:ahead|in front|behind))"),
)
CONTEXT_KEYWORDS: tuple[tuple[str, str], ...] = (
    (voc.AT_THE_INTERSECTION, voc.INTERSECTION_RX),
    (voc.ON_THE_CROSSWALK, r"crosswalk|zebra|pedestrian crossing"),
    (voc.ON_THE_SIDEWALK, r"sidewalk|pavement|footpath|walkway|footway"),
    (voc.BY_THE_CURB, r"\bcurb|\bkerb|roadside|side of the road|edge of the road|shoulder|parking"),
    (voc.IN_THE_ONCOMING_LANE, r"oncoming|opposite|opposing|towards? (?:us|me|ego|our car)"),
    (voc.ON_THE_ROAD, r"\broad\b|\bstreet\b|\blane\b|roadway|carriageway"),
)

#: Colour names the captioner confuses or people use interchangeably (symmetric).
SIMILAR_COLORS: frozenset[frozenset[str]] = frozenset(
    frozenset(p)
    for p in (
        ("white", "silver"),
        ("silver", "gray"),
        ("gray", "black"),
        ("beige", "white"),
        ("beige", "brown"),
        ("orange", "red"),
        ("orange", "yellow"),
        ("orange", "brown"),
        ("pink", "red"),
        ("pink", "purple"),
        ("purple", "blue"),
        ("yellow", "beige"),
    )
)

#: Query subtype -> caption subtypes it also fits, with a factor (1 = same thing). Others get
#: ``subtype_mismatch``. "car" is a generic passenger car.
SUBTYPE_FIT: dict[str, dict[str, float]] = {
    "car": {"sedan": 1.0, "hatchback": 1.0, "SUV": 1.0, "van": 0.3, "pickup truck": 0.3},
    "sedan": {"sedan": 1.0, "hatchback": 0.3},
    "hatchback": {"hatchback": 1.0, "sedan": 0.3},
    "SUV": {"SUV": 1.0, "van": 0.3, "pickup truck": 0.3},
    "van": {"van": 1.0, "SUV": 0.3},
    "pickup truck": {"pickup truck": 1.0, "truck": 0.5, "SUV": 0.3},
    "truck": {"truck": 1.0, "pickup truck": 0.5},
    "bus": {"bus": 1.0},
    "motorcycle": {"motorcycle": 1.0},
    "bicycle": {"bicycle": 1.0},
    "adult": {"adult": 1.0},
    "child": {"child": 1.0},
    "traffic cone": {"traffic cone": 1.0},
    "barrier": {"barrier": 1.0},
    "pole": {"pole": 1.0},
    "stop sign": {"stop sign": 1.0, "sign": 0.6},
    "speed limit sign": {"speed limit sign": 1.0, "sign": 0.6},
    "parking sign": {"parking sign": 1.0, "sign": 0.6},
}
