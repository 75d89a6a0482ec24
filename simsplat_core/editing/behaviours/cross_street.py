"""Crossing the street (pedestrians)."""

from simsplat_core.editing.behaviours.declaration import AgentKind, BehaviourDecl, Intent, LabelCheck
from simsplat_core.editing.behaviours.gait import GAIT_VERBS, STANDING_MPS, WALK_MPS, set_gait_of
from simsplat_core.editing.behaviours.jaywalk import take_jaywalking
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.parse import chunks
from simsplat_core.editing.parse.predicate import PredicateWork
from simsplat_core.scenario import vocabulary as voc

_CROSSABLE = (r"(?: over)?(?: (?:the|a) (?:street|road|lane|lanes|carriageway|crosswalk|zebra crossing|"
              + voc.INTERSECTION_RX + r"))?")


def parse_cross_street(w: PredicateWork) -> None:
    """"cross the street", "run across the road", "waiting to cross" -> ``cross_street`` (and the gait the verb
    says); jaywalking's words (``jaywalk.take_jaywalking``) -> ``cross_street`` and ``jaywalk``."""
    jaywalking = take_jaywalking(w)
    about_to = r"(?:(?:" + "|".join(sorted(chunks.TO_KEEPERS)) + r") to )?"  # "waiting to cross"
    crossed = w.take(about_to + r"(?:(?:cross|crosses|crossing)" + _CROSSABLE + r"|(?:(?:" + GAIT_VERBS["run"] + "|"
                     + GAIT_VERBS["walk"]
                     + r"|go|goes|head|heads|step|steps|hurry|hurries|make (?:his|her|their|"
                       r"its) way)(?: out)? (?:across"
                     r"|over)(?: (?:the )?(?:street|road|lane|lanes|carriageway))?))"
                     r"(?: (?:at|on|using|via|along) (?:the |a )?(?:crosswalk|zebra(?: crossing)?|"
                     r"pedestrian crossing))?",
                     lambda m: set_gait_of(w, m.group(0)))
    if crossed or jaywalking:
        w.set("cross_street", True)
    if jaywalking:
        w.set("jaywalk", True)


def _labelled_crossing(asked: bool, motion: str) -> bool:
    """Whether the motion class ``motion`` is one of crossing the street (either way, or undirected)."""
    return CROSS_STREET.motion_classes.get(motion) == "cross"


def crossing_speed(behaviour: Behaviour, current: float, kind: AgentKind) -> float | None:
    """A standing person asked to cross walks (:data:`gait.WALK_MPS`); a moving one keeps its pace."""
    return WALK_MPS if behaviour.cross_street and current < STANDING_MPS else None


CROSS_STREET = BehaviourDecl(
    "cross_street",
    fields=("cross_street",),
    agent="pedestrian",
    words="crossing the street",
    intents=(Intent("cross", fields={"cross_street": True}, phrases=("cross the street", "walk across the road")),),
    motion_classes={voc.CROSSING_LEFT_TO_RIGHT: "cross", voc.CROSSING_RIGHT_TO_LEFT: "cross", voc.CROSSING: "cross"},
    proposal_forms={
        "ped_cross": (
            "Make {T} cross the street.",
            "Have {T} walk across the road.",
        ),
        "ped_run_across": (
            "Make {T} run across the road.",
            "Have {T} sprint across the street.",
        ),
    },
    prompt_forms={
        "pedestrian_cross": (
            "Make {T} cross the street.",
            "{T} should walk across the road.",
            "Have {T} cross over to the other side of the street.",
        ),
    },
    parse_rule=parse_cross_street,
    label_check=LabelCheck("cross_street", _labelled_crossing, lambda asked: "not crossing the street"),
    speed_rule=crossing_speed,
)
