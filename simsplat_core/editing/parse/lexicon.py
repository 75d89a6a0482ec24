"""The edit parser's words: what verbs ask for which op, what starts a predicate, what an intent changes.

Object nouns, colours and garments are the grounding lexicon's (``language.grounding.parse``): this module adds
only what editing needs beyond describing objects -- the verbs of the four ops, the words that end a noun
phrase, a few insertable things the grounding nouns lack ("barrel", "worker"), the non-objects a prompt may
name ("the sky"), and the *intents* an unknown verb may be mapped to by E5 (``editing.parse.semantic``). The
motion behaviours' own words (their intents, phrasings and motion classes) are declared in ``editing.behaviours``.
"""

from __future__ import annotations

from simsplat_core.editing.assets.procedural import STATIC_KINDS as PROCEDURAL_STATIC_KINDS
from simsplat_core.language.grounding.parse import LOWER_GARMENTS, NOUNS, UPPER_GARMENTS
from simsplat_core.scenario import vocabulary as voc

# ------------------------------------------------------------------------------------------------ ops

#: Verbs (canonical text, possibly several words) that remove what follows.
REMOVE_VERBS: tuple[str, ...] = (
    "remove", "delete", "erase", "eliminate", "get rid of", "take out", "take away", "drop", "ditch", "discard",
    "clear", "clear out", "clear away", "wipe out", "wipe", "scrub", "cut", "axe", "lose", "strip out", "zap",
    "nuke", "kill", "exclude", "omit", "purge", "dispose of", "do away with", "throw out", "toss out", "hide",
    "despawn", "un-spawn", "unspawn", "pull out",
)
#: Where a removed object goes ("take the van *out of the scene*"): never part of a description.
SCENE_PHRASES: tuple[str, ...] = ("out of the scene", "from the scene", "out of the picture", "out of the clip",
                                  "out of the video", "out of the frame")
#: Verbs that insert an indefinite noun phrase ("add a cone"); with a definite one ("put the van ...") they move it.
INSERT_VERBS: tuple[str, ...] = (
    "add", "insert", "put", "place", "spawn", "drop in", "drop off", "drop", "introduce", "create", "position",
    "stick", "plant", "set up", "set down", "set", "bring in", "bring", "generate", "park", "include", "throw in",
    "toss in", "pop in", "pop", "deploy", "station", "stand", "line up", "lay out", "lay", "build", "make", "have",
    "i want", "i need", "we need", "we want", "i would like", "we would like", "give me", "there should be",
    "there is", "there are", "let there be", "there needs to be", "i want to see", "show", "see",
)
#: Verbs of a replacement ("replace X with Y", "swap X for Y", "turn X into Y").
REPLACE_VERBS: tuple[str, ...] = ("replace", "swap out", "swap", "exchange", "switch out", "switch", "substitute",
                                  "trade", "change", "turn", "convert", "transform", "morph", "make")
#: Verbs that make their object do the predicate ("make the car stop", "have it turn left").
CAUSATIVES: tuple[str, ...] = (
    "make", "have", "let", "get", "tell", "ask", "force", "order", "instruct", "cause", "i want", "we want",
    "i would like", "we would like", "i need", "we need", "allow", "command", "want",
)
#: Verbs that take the edited object first and their complements after ("stop the van before the crosswalk",
#: "slow the bus down to 20 km/h"); the predicate is the verb, its particle and what follows the object.
TARGET_FIRST_VERBS: tuple[str, ...] = (
    "stop", "halt", "slow", "speed", "accelerate", "decelerate", "brake", "reverse", "back", "turn", "steer",
    "delay", "hold", "move", "shift", "pull", "park", "drive", "merge", "redirect", "reroute", "send", "nudge",
    "hurry", "freeze", "relocate", "reposition", "put", "place", "position", "bring",
)
#: Verbs whose object is placed, not described ("move the van 5 m behind the bus").
PLACING_VERBS: tuple[str, ...] = ("move", "put", "place", "position", "relocate", "reposition")
#: Particles a target-first verb may take after its object ("slow the bus down").
PARTICLES: tuple[str, ...] = ("down", "up", "over", "off", "out", "away", "around", "back", "in")

#: Verbs that change a speed ("*reduce* its speed", "*set* the speed of the bus to 30 km/h").
SPEED_VERBS: tuple[str, ...] = ("set", "change", "adjust", "bring", "reduce", "lower", "decrease", "cut", "drop",
                                "increase", "raise", "boost")
#: Base (and third-person) forms of verbs that start a predicate after the subject ("the car should *stop*").
PREDICATE_VERBS: frozenset[str] = frozenset(
    w + s
    for w in (*SPEED_VERBS,
        "stop", "halt", "slow", "speed", "accelerate", "decelerate", "brake", "reverse", "back", "turn", "go", "drive",
        "move", "change", "switch", "merge", "cut", "shift", "swerve", "veer", "pull", "park", "cross", "jaywalk",
        "walk", "run", "jog", "sprint", "stroll", "dash", "race", "rush", "hurry", "wait", "pause", "hold", "start",
        "begin", "leave", "depart", "follow", "tailgate", "trail", "chase", "tail", "overtake", "pass", "yield",
        "come", "keep", "continue", "proceed", "stay", "remain", "stand", "take", "hang", "head", "travel",
        "cruise", "ease", "hit", "slam", "floor", "step", "disappear", "vanish", "get", "do", "make", "set",
        "stomp", "jam", "idle", "freeze", "drift", "queue", "wander", "amble", "saunter", "bolt", "hop", "bear",
        "enter", "exit", "arrive", "approach", "fly", "jump", "explode", "dance", "honk", "float", "sing", "crash",
    )
    for s in ("", "s", "es")
) | frozenset({"be", "is", "are", "never", "not", "no", "always", "gradually", "slowly", "quickly", "suddenly",
               "immediately", "carefully", "gently"})
#: Words between a subject and its predicate ("the truck *should* drive at 15 m/s").
MODALS: tuple[str, ...] = (
    "should", "must", "shall", "will", "would", "can", "could", "may", "might", "needs to", "need to", "has to",
    "have to", "is to", "are to", "ought to", "is going to", "are going to", "is supposed to", "are supposed to",
    "to", ":", "is now going to", "has got to",
)
#: Polite or connective openings dropped from a clause ("could you", "then", "i want you to").
OPENINGS: tuple[str, ...] = (
    "can you", "could you", "would you", "will you", "can we", "could we", "i want you to", "i would like you to",
    "i need you to", "i would like to", "i want to", "we want to", "we need to", "i need to", "let us", "go ahead and",
    "try to", "we should", "you should", "now", "then", "also", "and", "just", "next", "finally", "lastly", "ok",
    "okay", "additionally", "after that", "afterwards", "and then", "but", "so", "hey", "hi", "first", "firstly",
    "second", "secondly", "simply", "please",
)
#: Words that end a clause whatever follows.
HARD_BREAKS: tuple[str, ...] = (";", ".", "!", "?", "then", "after that", "afterwards", "additionally")
#: Words that end a clause when a new clause starts after them.
SOFT_BREAKS: tuple[str, ...] = ("and", ",", "but", "while", "plus", "also")

# ------------------------------------------------------------------------------------------------ nouns

#: Pronouns that refer to an object mentioned before.
PRONOUNS: tuple[str, ...] = ("it", "them", "they", "him", "her", "he", "she", "that one", "this one", "the same one",
                             "those", "these", "itself", "themselves")
#: Ways to say the ego vehicle (an anchor only).
EGO_WORDS: tuple[str, ...] = (
    "the ego vehicle", "the ego car", "the ego", "ego vehicle", "ego car", "ego", "us", "me", "our car",
    "our vehicle", "my car", "my vehicle", "ourselves", "the camera car", "the camera", "the self-driving car",
    "our own car",
)
DETERMINERS: tuple[str, ...] = (
    "all of the", "all the", "each of the", "one of the", "any of the", "both of the", "the", "a", "an", "this",
    "that", "these", "those", "all", "every", "each", "both", "any", "another", "my", "our", "your", "its",
    "their", "his", "her", "one more", "another one",
)
#: Quantities before an asset noun that are not numbers, and how many objects they mean.
QUANTITY_PHRASES: dict[str, int] = {
    "a row of": 5, "a line of": 5, "a column of": 5, "a queue of": 4, "a group of": 4, "a bunch of": 4,
    "a cluster of": 4, "a set of": 4, "a stack of": 3, "a couple of": 2, "a couple": 2, "a pair of": 2,
    "a few": 3, "several": 4, "some": 3, "many": 6, "lots of": 6, "a lot of": 6, "a handful of": 4, "multiple": 3,
}
#: Count of an asset given as a bare plural ("add cones behind the truck").
PLURAL_COUNT = 3
#: Insertable things the grounding nouns lack: word -> (asset category, subtype or None).
EXTRA_ASSET_NOUNS: dict[str, tuple[str, str | None]] = {
    "barrel": ("static", "barrel"), "barrels": ("static", "barrel"), "drum": ("static", "barrel"),
    "drums": ("static", "barrel"), "traffic barrel": ("static", "barrel"), "traffic barrels": ("static", "barrel"),
    "delineator": ("static", "traffic cone"), "delineators": ("static", "traffic cone"),
    "road block": ("static", "barrier"), "roadblock": ("static", "barrier"), "roadblocks": ("static", "barrier"),
    "jersey barrier": ("static", "barrier"), "fence": ("static", "barrier"), "fences": ("static", "barrier"),
    "construction sign": ("static", "sign"), "construction signs": ("static", "sign"),
    "work sign": ("static", "sign"), "road work sign": ("static", "sign"), "sawhorse": ("static", "barrier"),
    "construction equipment": ("static", "construction equipment"), "generator": ("static", "construction equipment"),
    "worker": ("pedestrian", None), "workers": ("pedestrian", None), "officer": ("pedestrian", None),
    "officers": ("pedestrian", None), "policeman": ("pedestrian", None), "policewoman": ("pedestrian", None),
    "cop": ("pedestrian", None), "cops": ("pedestrian", None), "student": ("pedestrian", None),
    "students": ("pedestrian", None), "teenager": ("pedestrian", None), "toddler": ("pedestrian", "child"),
    "ambulance": ("vehicle", "van"), "ambulances": ("vehicle", "van"), "fire truck": ("vehicle", "truck"),
    "firetruck": ("vehicle", "truck"), "fire engine": ("vehicle", "truck"), "limo": ("vehicle", "car"),
    "limousine": ("vehicle", "car"), "police cruiser": ("vehicle", "car"), "cruiser": ("vehicle", "car"),
    "semi": ("vehicle", "truck"), "tractor": ("vehicle", "truck"), "camper": ("vehicle", "van"),
    "minibus": ("vehicle", "bus"), "school bus": ("vehicle", "bus"), "tram": ("vehicle", "bus"),
    "convertible": ("vehicle", "car"), "coupe": ("vehicle", "car"), "wagon": ("vehicle", "car"),
}
# every procedural static kind the bank can build, by its name and aliases, singular and plural ("an excavator",
# "a digger", "arrow boards"); the words above keep their broader subtypes
for _kind in PROCEDURAL_STATIC_KINDS.values():
    for _word in (_kind.subtype, *_kind.aliases):
        EXTRA_ASSET_NOUNS.setdefault(_word, ("static", _kind.subtype))
        EXTRA_ASSET_NOUNS.setdefault(_word + "s", ("static", _kind.subtype))
#: What grounding-noun categories become as an asset category.
ASSET_CATEGORY: dict[str, str] = {"vehicle": "vehicle", "pedestrian": "pedestrian", "static": "static",
                                  "sign": "static", "cyclist": "vehicle"}
#: Parts of the scene that are not objects: a prompt that edits them is refused.
NON_OBJECTS: tuple[str, ...] = (
    "sky", "road", "roads", "street", "streets", "lane", "lanes", "sidewalk", "sidewalks", "crosswalk", "building",
    "buildings", "tree", "trees", "weather", "sun", "rain", "snow", "fog", "clouds", "cloud", "grass", "ground",
    *voc.INTERSECTION_NOUNS, "lighting", "light", "lights", "night", "day", "time of day", "season", "scene",
    "world", "city", "house", "houses", "wall", "walls", "camera", "image", "picture", "video", "map", "asphalt",
)
#: Nouns of places and parts of the road (a phrase holding one is a place, not an appearance).
PLACE_NOUNS: tuple[str, ...] = (
    "street", "road", "lane", "lanes", "sidewalk", "pavement", "footpath", "walkway", "crosswalk", "zebra crossing",
    "zebra", "pedestrian crossing", *voc.INTERSECTION_NOUNS, "curb", "kerb", "side",
    "left", "right", "front", "back", "rear", "middle", "centre", "center", "corner", "shoulder", "roadside",
    "light", "lights", "traffic light", "traffic lights", "stop line", "scene", "lot", "parking lot", "spot", "edge",
    "block", "road work", "queue", "line", "traffic", "ego",
)
#: Other nouns that may head or end a noun phrase ("the red *one*", "a man with a *stroller*").
OTHER_NOUNS: tuple[str, ...] = ("one", "ones", "thing", "things", "object", "objects", "guy", "hat", "cap", "helmet",
                                "backpack", "bag", "umbrella", "stroller", "pram", "dog", "stripe", "stripes",
                                "everyone", "everybody", "everything", "agents")
#: Every noun that may head a noun phrase.
GARMENTS: frozenset[str] = frozenset((*UPPER_GARMENTS, *LOWER_GARMENTS))
HEAD_NOUNS: frozenset[str] = frozenset((*NOUNS, *UPPER_GARMENTS, *LOWER_GARMENTS, *EXTRA_ASSET_NOUNS, *PLACE_NOUNS,
                                        *OTHER_NOUNS, *NON_OBJECTS))
HEAD_NOUN_MAX_WORDS = max(len(n.split()) for n in HEAD_NOUNS)

# ------------------------------------------------------------------------------------------------ intents

#: Intents an unknown verb or predicate may mean. "remove" / "insert" / "replace" are ops; the others set
#: behaviour fields (``editing.behaviours.registry.INTENT_FIELDS``); "unsupported" marks phrasings to refuse.
UNSUPPORTED = "unsupported"
#: Imperative phrasings of the ops' intents (E5 passages; ``editing.parse.semantic`` adds the behaviours').
OP_PHRASES: dict[str, tuple[str, ...]] = {
    "remove": ("remove it from the scene", "delete it", "take it out of the scene", "get rid of it",
               "make it disappear", "erase it"),
    "insert": ("add one to the scene", "put a new one on the road", "place another one here"),
    "replace": ("replace it with a different one", "swap it for another one"),
}
#: Phrasings of what the editor cannot do (E5 passages of the intent :data:`UNSUPPORTED`).
UNSUPPORTED_PHRASES: tuple[str, ...] = (
    "fly", "change its colour", "paint it", "make it rain", "explode", "jump", "honk the horn", "turn on the lights",
    "dance", "sing", "make it bigger", "turn into an animal", "teleport", "make it invisible", "do a u-turn",
    "drive on the sidewalk", "crash")

#: The supported edits, for refusal messages.
SUPPORTED = (
    "I can insert, remove, replace, or change speed/stop/reverse/lane change/turn/delay/follow/cross: "
    "insert a vehicle, pedestrian or static object (cone, barrier, barrel, sign) at a place ('2 m to the left "
    "of the white van', 'in the left lane 30 m ahead', 'on the crosswalk', 'at (10, -3, 0)'); remove objects "
    "or groups ('all parked cars'); replace an object's appearance ('replace the van with a yellow taxi'); "
    "modify a vehicle's motion: speed (km/h, m/s, mph; 'twice as fast', '10 km/h slower'), accelerate / "
    "decelerate / brake hard, stop (at a time, before a crosswalk or intersection, behind an object), reverse, "
    "change lanes left/right, turn left/right or go straight at the next intersection, delay or start time, "
    "follow another vehicle; make a pedestrian cross the street, jaywalk, walk or run."
)
