"""Descriptions split into agent clauses and the relations between them.

    q = parse_description("a pedestrian crossing in front of ego while a car turns right")
    [c.text for c in q.clauses]          # ["a pedestrian crossing in front of ego", "a car turns right"]
    q.clauses[0].motions, q.clauses[0].sectors    # ("crossing",), ("in_front_of_ego",)

Rules (on ``grounding.parse.normalise``d text):

1. **Conjunction.** "while", "whilst", "as", "when", "and", "with" (and "at the same time as") split the
   text into clauses when the part after them names an agent of its own (a ``grounding.parse.NOUNS`` noun):
   "a car slowing down and stopping" stays one clause, "a parked van and a person standing" is two. Every
   clause must hold in the same frame (different objects may satisfy them).
2. **Relations** between two agents of one clause: "<A> following / behind / tailing <B>" (A drives behind B
   in B's lane), "<A> ahead of / in front of <B>" (B follows A), "<A> next to / beside / alongside <B>".
   The object <B> is a clause of its own (``AgentClause.related``). Ego words ("us", "ego", "our car",
   "me") are not agents: "in front of us" stays a sector of A.
3. **Ego lane.** "the ego lane blocked by <B>", "<B> blocking our lane", "<B> in our lane": <B> must be in
   the ego's lane ahead of it (``AgentClause.in_ego_lane``); "blocked" / "blocking" also asks it to stand.
4. Each clause is then a grounding query (``grounding.parse.parse_query``): category, subtype, colours, motion
   phrase, sector and context phrases; the motion phrase names motion classes through the query lexicon
   (``grounding.lexicon.MOTION_KEYWORDS``), the location phrases the sector / context classes.
5. **The ego as a subject.** A clause whose subject is the ego ("we turn left", "as our car slows down",
   "when the ego is stopped at the intersection") is ``AgentClause.is_ego``: only the ego's own per-frame
   motion and map context answer it. Relations may name the ego as their object: "a car following us"
   (``related`` is an ego clause), "beside us"; "in front of us" / "behind us" stay sectors.
   "<A> cutting in front of us" / "cutting in ahead of ego" / "pulling into our lane" is a cut-in
   (``AgentClause.cut_in``): a lane change ahead of the ego that closes in on its path.
6. **Counts.** "two pedestrians", "a pair of cars", "three vehicles": ``AgentClause.count`` distinct objects must
   hold at once; "together" / "side by side" also asks them to be within ``SearchConfig.together_m``.
   "a group of" / "several" / "some" + plural mean two or more.
7. **Question and request wording** ("where does a truck turn left?", "any cars reversing", "are there
   pedestrians crossing", "find / show me ...") is dropped before parsing.
8. **Places the maps do not have** ("highway", "motorway", "tunnel", "roundabout", ...) are kept in
   ``AgentClause.unknown_places``: such a clause holds nowhere, and the message says why.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

from simsplat_core.language.grounding.lexicon import (
    CONTEXT_KEYWORDS,
    MOTION_KEYWORDS,
    PEDESTRIAN_MERGED,
    SECTOR_KEYWORDS,
)
from simsplat_core.language.grounding.parse import NOUNS, ParsedQuery, normalise, parse_query
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.trajectory import agent_kind

#: Relation names.
FOLLOWING = "following"
LEADING = "leading"
BESIDE = "beside"

#: Words that link two clauses that must hold at once.
_CONJUNCTION_RX = re.compile(r"(?<![\w-])(?:at the same time as|while|whilst|as|when|and|with)(?![\w-])")
_NOUN_ALT = "|".join(sorted(map(re.escape, NOUNS), key=len, reverse=True))
_NOUN_RX = re.compile(r"(?<![\w-])(?:" + _NOUN_ALT + r")(?![\w-])")
_EGO_RX = re.compile(r"(?<![\w-])(?:us|me|ego|we|the ego(?: vehicle| car)?|our (?:car|vehicle)|my (?:car|vehicle))"
                     r"(?![\w-])")
_RELATION_RX = re.compile(
    r"(?<![\w-])(?P<rel>following|follows|follow|tailing|tails|behind|ahead of|in front of|next to|beside|alongside)"
    r" (?P<obj>(?:the|a|an|another|some|other) (?:(?!while|whilst|as|when|and)[\w-]+ ){0,3}?(?:" + _NOUN_ALT + r"))"
    r"(?![\w-])")
_REL_NAME = {"following": FOLLOWING, "follows": FOLLOWING, "follow": FOLLOWING, "tailing": FOLLOWING,
             "tails": FOLLOWING, "leading": LEADING, "leads": LEADING, "behind": FOLLOWING, "ahead of": LEADING,
             "in front of": LEADING, "next to": BESIDE, "beside": BESIDE, "alongside": BESIDE}
_EGO_LANE_RX = re.compile(r"(?:the )?(?:ego|our|my)(?: vehicle's| car's)? lane (?:is |being )?"
                          r"(?P<verb>blocked|obstructed)"
                          r" by (?P<obj>.+)")
_IN_EGO_LANE_RX = re.compile(r"(?P<verb>blocking|obstructing|in|sitting in|standing in|stopped in) "
                             r"(?:the )?(?:ego|our|my)(?: vehicle's| car's)? lane")
#: Short words people type for agents that the grounding lexicon does not list.
ALIASES = {"ped": "pedestrian", "peds": "pedestrians", "pedestrian's": "pedestrian", "ppl": "people",
           "veh": "vehicle", "vehs": "vehicles"}
_ALIAS_RX = re.compile(r"(?<![\w-])(" + "|".join(map(re.escape, ALIASES)) + r")(?![\w-])")
#: The ego as a clause's subject (after an optional leading conjunction), with its verb's copula.
_EGO_SUBJECT_RX = re.compile(
    r"^(?:(?:while|whilst|as|when|and|with) )?(?:we(?:'re| are| were)?|i(?:'m| am)?|ego(?: is)?|"
    r"the ego(?: vehicle| car)?(?: is)?|(?:our|my) (?:own )?(?:car|vehicle)(?: is)?|"
    r"the (?:self-driving|autonomous) (?:car|vehicle)(?: is)?)(?![\w'-])(?! lane\b) ?")
_EGO_OBJECT = r"us|me|ego|the ego(?: vehicle| car)?|our (?:car|vehicle)|my (?:car|vehicle)"
#: Relations whose object is the ego ("a car following us"); "in front of us" / "behind us" stay sectors.
_EGO_RELATION_RX = re.compile(
    r"(?<![\w-])(?P<rel>following|follows|follow|tailing|tails|leading|leads|next to|beside|alongside) "
    r"(?:" + _EGO_OBJECT + r")(?![\w-])")
_CUT_IN_RX = re.compile(
    r"(?<![\w-])(?:cut|cuts|cutting|pull|pulls|pulling|merg\w*|swerv\w*)(?: in| into)?"
    r" (?:in front of|ahead of|into|in) (?:" + _EGO_OBJECT + r"|(?:our|my|the ego's?) lane)(?![\w-])")
_LEADING_CONJUNCTION_RX = re.compile(r"^(?:while|whilst|as|when|and|with|at the same time as) ")
#: Question and request wording dropped before parsing (rule 7).
_REQUEST_RX = re.compile(
    r"^(?:(?:please )?(?:find|show|show me|search for|look for|list|get|give me)(?: all| every| me)? |"
    r"(?:where|when) (?:does|do|did|is|are|was|were) |(?:is|are) there (?:any )?|any |"
    r"(?:do|does|did) (?:we|you) see (?:any )?)")
_COUNT_WORDS = {"two": 2, "a pair of": 2, "a couple of": 2, "both": 2, "three": 3, "four": 4, "five": 5,
                "a group of": 2, "several": 2, "multiple": 2}
_COUNT_RX = re.compile(r"^(?P<n>" + "|".join(map(re.escape, sorted(_COUNT_WORDS, key=len, reverse=True)))
                       + r") ")
_TOGETHER_RX = re.compile(r"(?<![\w-])(?:together|side by side|in a group|as a group|next to each other)(?![\w-])")
#: Motion classes another one implies (a halt is a slow-down).
IMPLIED_MOTIONS = {voc.SLOWING_DOWN: (voc.STOPPING,)}
_SUBJECT_CROSSING_RX = re.compile(r"^((?:a|an|the|one|some|any) )?pedestrian(s?) crossing(?![\w-])")
#: Place words no map of this project has (a clause naming one holds nowhere).
UNKNOWN_PLACES = ("highway", "motorway", "freeway", "expressway", "tunnel", "bridge", "roundabout", "toll",
                  "parking lot", "car park", "garage", "railway", "level crossing", "bus stop", "driveway")
_UNKNOWN_RX = re.compile(r"(?<![\w-])(" + "|".join(map(re.escape, UNKNOWN_PLACES)) + r")s?(?![\w-])")


@dataclass(frozen=True)
class AgentClause:
    """One agent the description asks for.

    Attributes:
        text: the clause as split off the description.
        parsed: its grounding parse (category, subtype, colours, motion / location phrases).
        motions: motion classes the clause allows (``vocabulary`` names; ``crossing`` = any crossing); empty = any.
        crossing_direction: ``"left_to_right"`` / ``"right_to_left"`` or ``None``.
        sectors: ego sectors allowed (empty = any).
        contexts: map contexts required (all of them; empty = any).
        in_ego_lane: the agent must be in the ego's lane ahead of it.
        relation: ``FOLLOWING`` / ``LEADING`` / ``BESIDE`` to ``related`` (``""``: none).
        related: the other agent of the relation.
        unknown_places: place words no map has ("highway").
        is_ego: the subject is the ego itself.
        cut_in: the subject cuts in ahead of the ego (module docstring, rule 5).
        count: how many distinct objects must hold at once (rule 6); ``together``: within reach of each other.
    """

    text: str
    parsed: ParsedQuery
    motions: tuple[str, ...] = ()
    crossing_direction: str | None = None
    sectors: tuple[str, ...] = ()
    contexts: tuple[str, ...] = ()
    in_ego_lane: bool = False
    relation: str = ""
    related: AgentClause | None = None
    unknown_places: tuple[str, ...] = ()
    is_ego: bool = False
    cut_in: bool = False
    count: int = 1
    together: bool = False

    @property
    def kinds(self) -> tuple[str, ...]:
        """Agent kinds (``vehicle`` / ``pedestrian``) the subject can be; both when it names none."""
        kinds = {agent_kind(c) for c in self.parsed.categories} - {None}
        return tuple(k for k in (voc.VEHICLE, voc.PEDESTRIAN) if not kinds or k in kinds)

    def describe(self) -> str:
        """A short phrase for messages ("a car following the bus": the clause with its relation, if any)."""
        if self.related is None or not self.relation:
            return self.text
        return f"{self.text} ({self.relation} {'the ego' if self.related.is_ego else self.related.text})"


@dataclass(frozen=True)
class SearchQuery:
    """A parsed description: clauses that must hold in the same frames."""

    text: str
    clauses: tuple[AgentClause, ...] = field(default_factory=tuple)


def _has_agent(text: str) -> bool:
    """An agent noun of its own, or the ego as the subject ("we turn left")."""
    return bool(_NOUN_RX.search(_EGO_RX.sub(" ", text))) or bool(_EGO_SUBJECT_RX.match(text.strip()))


def split_clauses(norm: str) -> list[str]:
    """Split normalised text at conjunctions followed by an agent of their own (module docstring, rule 1)."""
    parts: list[str] = []
    start = 0
    for m in _CONJUNCTION_RX.finditer(norm):
        left, right = norm[start:m.start()].strip(), norm[m.end():]
        nxt = _CONJUNCTION_RX.search(right)
        right_part = right[: nxt.start()] if nxt else right
        if left and _has_agent(left) and _has_agent(right_part) and not _RELATION_TAIL_RX.search(left):
            parts.append(left)
            start = m.end()
    parts.append(norm[start:].strip())
    return [p for p in parts if p]


#: A clause that ends in a relation word waits for its object ("a car behind ... and"): never split there.
_RELATION_TAIL_RX = re.compile(r"(?:following|behind|ahead of|in front of|next to|beside|by)$")


def motion_classes(parsed: ParsedQuery, kinds: tuple[str, ...]) -> tuple[str, ...]:
    """Motion classes the clause's motion phrase names, for the agent kinds it can refer to (lexicon)."""
    if not parsed.motion:
        return ()
    allowed: set[str] = set()
    if voc.VEHICLE in kinds:
        allowed |= set(voc.VEHICLE_MOTION.names)
    if voc.PEDESTRIAN in kinds:
        allowed |= set(PEDESTRIAN_MERGED)
    hits = [c for rx, named in MOTION_KEYWORDS if re.search(rx, parsed.motion) for c in named if c in allowed]
    if voc.CROSSING in hits:
        hits = [c for c in hits if c != voc.WALKING_ALONG]  # "walking across" is a crossing
    hits += [c for h in hits for c in IMPLIED_MOTIONS.get(h, ()) if c in allowed]
    return tuple(dict.fromkeys(hits))


def location_classes(parsed: ParsedQuery) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """``(sectors, contexts)`` the clause's location phrases name (``ON_THE_ROAD`` only when nothing else)."""
    sectors = tuple(name for name, rx in SECTOR_KEYWORDS if parsed.sector and re.search(rx, parsed.sector))
    contexts = [name for name, rx in CONTEXT_KEYWORDS if parsed.context and re.search(rx, parsed.context)]
    if voc.ON_THE_ROAD in contexts and len(contexts) > 1:
        contexts.remove(voc.ON_THE_ROAD)
    return sectors, tuple(contexts)


def parse_clause(text: str) -> AgentClause:
    """One agent clause, with its relation object or ego-lane phrase if any (module docstring, rules 2-5)."""
    text = _LEADING_CONJUNCTION_RX.sub("", text.strip())
    ego = _EGO_SUBJECT_RX.match(text)
    if ego:  # "we turn left": the ego is the subject; parse the rest as a car's clause
        text = "a vehicle " + text[ego.end():]
    count, together = 1, False
    n = _COUNT_RX.match(text)
    if n:
        count = _COUNT_WORDS[n.group("n")]
        text = "a " + text[n.end():]
    elif re.match(r"(?:some|many|the) [\w-]+s(?![\w'-])", text) and re.search(r"\btogether\b|\bgroup\b", text):
        count = 2
    if _TOGETHER_RX.search(text):
        together = count > 1
        text = _TOGETHER_RX.sub(" ", text).strip()
    cut = _CUT_IN_RX.search(text)
    if cut:
        text = (text[: cut.start()] + " " + text[cut.end():]).strip()
    in_ego_lane = False
    related: AgentClause | None = None
    relation = ""
    blocked = False
    m = _EGO_LANE_RX.search(text)
    if m:  # "the ego lane blocked by a parked truck": the truck is the agent
        text, in_ego_lane, blocked = m.group("obj"), True, True
    m2 = _IN_EGO_LANE_RX.search(text)
    if m2:
        in_ego_lane = True
        blocked = blocked or m2.group("verb") in ("blocking", "obstructing")
        text = (text[: m2.start()] + " " + text[m2.end():]).strip()
    ego_rel = _EGO_RELATION_RX.search(text)
    rel = _RELATION_RX.search(text)
    if ego_rel:  # "a car following us": the related agent is the ego
        relation = _REL_NAME[ego_rel.group("rel")]
        related = replace(parse_clause("a vehicle"), text="ego", is_ego=True)
        text = (text[: ego_rel.start()] + " " + text[ego_rel.end():]).strip()
    elif rel and not _EGO_RX.fullmatch(rel.group("obj").split(" ", 1)[-1]):
        relation = _REL_NAME[rel.group("rel")]
        related = parse_clause(re.sub(r"^(?:another|other|some) ", "a ", rel.group("obj")))
        text = (text[: rel.start()] + " " + text[rel.end():]).strip()
    unknown = tuple(dict.fromkeys(u.group(1) for u in _UNKNOWN_RX.finditer(text)))
    # a clause opening on "a pedestrian crossing" is a walker, not a crosswalk
    text = _SUBJECT_CROSSING_RX.sub(r"\1pedestrian\2 who is crossing", text)
    parsed = parse_query(text or "object")
    kinds_clause = AgentClause(text, parsed)
    motions = motion_classes(parsed, kinds_clause.kinds)
    if blocked and not motions:
        motions = (voc.STOPPED, voc.PARKED)
    if cut:
        motions = (voc.CHANGING_LANE_LEFT, voc.CHANGING_LANE_RIGHT)
    sectors, contexts = location_classes(parsed)
    return AgentClause(text=text, parsed=parsed, motions=motions, crossing_direction=parsed.crossing_direction,
                       sectors=sectors, contexts=contexts, in_ego_lane=in_ego_lane, relation=relation,
                       related=related, unknown_places=unknown, is_ego=bool(ego), cut_in=bool(cut), count=count,
                       together=together)


#: An agent noun phrase starting a clause: a determiner, up to three words that are not determiners, a noun.
_DETERMINER = r"(?:a|an|the|some|another|any|one|two|three|several)"
_AGENT_START_RX = re.compile(r"(?<![\w-])" + _DETERMINER + r" (?:(?!" + _DETERMINER + r" )[\w-]+ ){0,3}?(?:"
                             + _NOUN_ALT + r")(?![\w-])")


#: Words after which a noun phrase is their object, not a new clause's subject.
_OBJECT_TAIL_RX = re.compile(r"(?<![\w-])(?:following|follows|tailing|behind|of|to|beside|alongside|by|at|on|in|"
                             r"near|past|from|with|than|overtaking|passing)$")


def main_clause_first(norm: str) -> str:
    """A description that opens with its subordinate clause ("while we turn left(,) a pedestrian waits on the
    sidewalk") turned round ("a pedestrian waits on the sidewalk while we turn left"), so that the conjunction split
    (rule 1) sees it; other text as it is. The main clause starts at the first agent noun phrase after the opening
    clause has an agent of its own and that is no object of a relation or preposition ("following the bus")."""
    lead = _LEADING_CONJUNCTION_RX.match(norm)
    if lead is None:
        return norm
    for m in _AGENT_START_RX.finditer(norm, lead.end()):
        opening = norm[lead.end():m.start()].strip()
        if opening and _has_agent(opening) and not _OBJECT_TAIL_RX.search(opening):
            return f"{norm[m.start():].strip()} {lead.group(0).strip()} {opening}"
    return norm


def parse_description(text: str) -> SearchQuery:
    """Parse a search description (module docstring).

    Raises:
        ValueError: the description is empty.
    """
    if not text or not text.strip():
        raise ValueError("empty search description")
    norm = main_clause_first(_REQUEST_RX.sub("", _ALIAS_RX.sub(lambda m: ALIASES[m.group(1)], normalise(text))))
    return SearchQuery(text, tuple(parse_clause(part) for part in split_clauses(norm)))
