"""Edit proposals from a scene's grounded facts: feasible, diverse over the six edit categories, safety-critical
first, deterministic for a seed.

    proposals = propose_edits(scene_facts(ctx), count=6, seed=0)
    proposals[0].prompt      # "Add a pedestrian who jaywalks across the road 31 m ahead of us."
    proposals[0].category    # "add_pedestrian"; .kind "jaywalker"; .safety_critical True

Every proposal kind (:data:`KINDS`) belongs to one category (:data:`EDIT_CATEGORIES`) and lists its feasible
instances in the scene, best first, each worded afresh (``rule_wording``):

* add_vehicle -- a car cutting in from the next lane, a car ahead in our lane braking hard, a car in the
  oncoming lane, a fast car in the next lane, a car close behind a moving vehicle;
* add_static -- cones or another obstacle in our lane, cones closing the next lane, an object on the road, an
  object by a standing vehicle;
* add_pedestrian -- a jaywalker or a runner crossing the road ahead (on plain road only: off crosswalks and
  intersections), a walker on the crosswalk ahead or on the sidewalk;
* modify_vehicle -- a moving vehicle braking hard, changing lanes (where a lane runs its way on that side),
  slowing down, speeding up (with room ahead), turning (where a turn is within reach), starting later; a
  standing one reversing (room behind) or pulling out (room ahead); any one replaced by a bank asset;
* modify_pedestrian -- a pedestrian on the sidewalk jaywalking, running across or crossing; a walking one
  running, stopping or waiting;
* remove -- one object, or every object of a caption.

Objects are only acted on when a description tells them apart (``rule_wording.referring_phrase``) and a camera
sees them; inserts go where the road allows it -- within the ego lane's length, at most :data:`INSERT_MAX_M`
ahead, on a spot no agent takes at the reference frame -- and only with assets the bank has.

Selection (:func:`propose_edits`): the categories in a seeded order, one proposal per category per round; in
each category the kinds in a seeded order with the safety-critical ones first, taking turns; an object already
acted on is used again only when nothing else is left; repeated wordings are dropped.
"""

from __future__ import annotations

import logging
import zlib
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from simsplat_core.mining.rule_wording import (
    asset_phrase,
    distance_phrase,
    duration_phrase,
    group_phrase,
    lookalikes,
    pick,
    realise,
    referring_phrase,
    row_phrase,
    speed_phrase,
)
from simsplat_core.mining.scene_fact_records import AgentFacts, AssetFacts, SceneFacts
from simsplat_core.scenario import vocabulary as voc

logger = logging.getLogger(__name__)

#: The edit categories (the ``editing`` evaluation table's, SIMSplat Table 3).
EDIT_CATEGORIES: tuple[str, ...] = ("add_vehicle", "add_static", "add_pedestrian", "modify_vehicle",
                                    "modify_pedestrian", "remove")
#: Inserts go at least / at most this far ahead (m): closer hides the reaction, farther is a few pixels.
INSERT_MIN_M = 12.0
INSERT_MAX_M = 40.0
#: Distance kept to the end of the ego's lane path (m).
LANE_END_MARGIN_M = 10.0
#: An inserted vehicle's (object's, pedestrian's) spot is taken when an agent of that area is this close along the
#: road at the reference frame (m); the editor then finds room nearby or refuses.
SPOT_CLEAR_M = 10.0
SMALL_SPOT_CLEAR_M = 5.0
#: Least share of frames a camera must see an object for it to be acted on.
MIN_VISIBLE_SHARE = 0.15
#: Least speed (m/s) of a vehicle asked to stop or change lanes.
MIN_MOVING_MPS = 2.0
#: Free distance (m) a reversing / pulling-out / speeding-up / delayed vehicle needs.
REVERSE_ROOM_M = 8.0
PULL_OUT_ROOM_M = 25.0
SPEED_UP_ROOM_M = 40.0
DELAY_ROOM_M = 20.0


@dataclass(frozen=True)
class Proposal:
    """One proposed edit.

    Attributes:
        prompt: the words.
        category: one of :data:`EDIT_CATEGORIES`.
        kind: the proposal kind (a ``rule_wording.FORMS`` key).
        safety_critical: the edit makes the scene critical for the ego (a jaywalker, a cut-in, a hard stop, an
            obstacle in the lane, a car reversing or pulling out).
        target_id: the scene object it acts on or is placed by (``None``: none).
    """

    prompt: str
    category: str
    kind: str
    safety_critical: bool
    target_id: str | None = None


Builder = Callable[[SceneFacts, np.random.Generator], list[Proposal]]


@dataclass(frozen=True)
class ProposalKind:
    """A kind of proposal: its category, whether it is safety-critical, and the builder of its feasible
    instances (best first)."""

    name: str
    category: str
    safety_critical: bool
    build: Builder


# ---------------------------------------------------------------------------------------------- feasibility
def _visible_targets(facts: SceneFacts, kind: str, ok: Callable[[AgentFacts], bool]) -> list[AgentFacts]:
    """Objects of ``kind`` a camera sees that pass ``ok``, nearest to the ego first."""
    found = [a for a in facts.of_kind(kind) if a.visible_share >= MIN_VISIBLE_SHARE and ok(a)]
    return sorted(found, key=lambda a: (a.ahead_m < 0, a.distance_m))


def _spot_clear(facts: SceneFacts, areas: tuple[str, ...], ahead_m: float, clear_m: float) -> bool:
    """No agent in ``areas`` within ``clear_m`` of ``ahead_m`` along the road."""
    return not any(a.area in areas and abs(a.ahead_m - ahead_m) < clear_m for a in facts.agents)


#: A lane change takes about this long (s) ...
LANE_CHANGE_S = 4.0
#: ... and at least this much plain road (m) beyond where it starts.
LANE_CHANGE_MIN_M = 20.0


def _lane_reach(facts: SceneFacts) -> float:
    return min(INSERT_MAX_M, facts.road.lane_ahead_m - LANE_END_MARGIN_M)


def _distances(facts: SceneFacts, lo: float, hi: float, areas: tuple[str, ...], rng: np.random.Generator,
               plain: bool = False, clear_m: float = SPOT_CLEAR_M, most: int = 2, room_m: float = 0.0) -> list[float]:
    """Up to ``most`` whole-metre distances ahead within ``[lo, hi]`` (on plain road when ``plain``, within the ego
    lane's reach; with ``room_m``, on plain road that goes on at least ``room_m`` further, e.g. for a lane change to
    finish before the next intersection or crosswalk) that no agent of ``areas`` is within ``clear_m`` of, drawn at
    random."""
    hi = min(hi, _lane_reach(facts))
    if room_m > 0.0:
        spans: tuple[tuple[float, float], ...] = tuple(
            (a, min(b - room_m, hi)) for a, b in facts.road.plain_road_within(lo, np.inf) if min(b - room_m, hi) >= a)
    else:
        spans = facts.road.plain_road_within(lo, hi) if plain else ((lo, hi),) if hi >= lo else ()
    whole = sorted({float(d) for a, b in spans for d in range(int(np.ceil(a)), int(np.floor(b)) + 1)})
    clear = [d for d in whole if _spot_clear(facts, areas, d, clear_m)]
    picks = rng.permutation(len(clear))[:most]
    return [clear[i] for i in sorted(picks)]


def _assets(facts: SceneFacts, category: str, subtypes: Iterable[str] | None = None) -> tuple[AssetFacts, ...]:
    keep = tuple(subtypes) if subtypes is not None else None
    return tuple(a for a in facts.assets_of(category) if keep is None or a.subtype in keep)


def _sides(facts: SceneFacts) -> list[str]:
    return [s for s, has in (("left", facts.road.left_lane), ("right", facts.road.right_lane)) if has]


def _other(side: str) -> str:
    return "right" if side == "left" else "left"


def _named(facts: SceneFacts, agents: Iterable[AgentFacts], rng: np.random.Generator) -> list[tuple[AgentFacts, str]]:
    """The agents with a description that tells them apart, and that description."""
    out = []
    for agent in agents:
        phrase = referring_phrase(agent, facts, rng)
        if phrase is not None:
            out.append((agent, phrase))
    return out


# ---------------------------------------------------------------------------------------------- builders
def _inserts(kind: str, facts: SceneFacts, rng: np.random.Generator, category: str, distances: list[float],
             assets: tuple[AssetFacts, ...], safety: bool, **slots: str) -> list[Proposal]:
    """One proposal per distance, with a random asset of ``assets`` (none: no proposal)."""
    if not assets:
        return []
    out = []
    for d in distances:
        asset = assets[int(rng.integers(len(assets)))]
        words = {"A": asset_phrase(asset, rng), "P": asset_phrase(asset, rng), "d": distance_phrase(d, rng), **slots}
        out.append(Proposal(realise(kind, rng, **words), category, kind, safety))
    return out


def _cut_in(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    """A car put in a lane beside ours that changes into ours ahead of us, where the plain road goes on long enough
    for the move (:data:`LANE_CHANGE_S` at the ego's speed, at least :data:`LANE_CHANGE_MIN_M`)."""
    room = max(LANE_CHANGE_MIN_M, LANE_CHANGE_S * facts.road.ego_speed_mps)
    out = []
    for side in _sides(facts):
        ds = _distances(facts, INSERT_MIN_M, 25.0, (f"{side}_lane", "ego_lane"), rng, room_m=room)
        out += _inserts("cut_in", facts, rng, "add_vehicle", ds, _assets(facts, "vehicle"), True, side=side,
                        other=_other(side))
    return out


def _lead_brake(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    lo = max(15.0, 2.5 * facts.road.ego_speed_mps)
    ds = _distances(facts, lo, 35.0, ("ego_lane",), rng)
    return _inserts("lead_brake", facts, rng, "add_vehicle", ds, _assets(facts, "vehicle"), True)


def _oncoming(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    if facts.road.lanes_oncoming == 0:
        return []
    ds = _distances(facts, 20.0, INSERT_MAX_M, ("oncoming_lane",), rng, clear_m=SMALL_SPOT_CLEAR_M)
    return _inserts("oncoming", facts, rng, "add_vehicle", ds, _assets(facts, "vehicle"), False)


def _side_lane_fast(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    out = []
    for side in _sides(facts):
        ds = _distances(facts, INSERT_MIN_M, 25.0, (f"{side}_lane",), rng)
        speed = speed_phrase(facts.road.ego_speed_mps + float(rng.uniform(3.0, 6.0)), rng)
        out += _inserts("side_lane_fast", facts, rng, "add_vehicle", ds, _assets(facts, "vehicle"), False, side=side,
                        v=speed)
    return out


def _tailgate(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    assets = _assets(facts, "vehicle")
    if not assets:
        return []
    anchors = _visible_targets(facts, "vehicle", lambda a: a.moving and a.room_behind_m >= 12.0)
    out = []
    for anchor, phrase in _named(facts, anchors, rng):
        asset = assets[int(rng.integers(len(assets)))]
        d = float(min(int(rng.integers(6, 11)), anchor.room_behind_m - 3.0))
        words = {"A": asset_phrase(asset, rng), "T": phrase, "d": distance_phrase(d, rng)}
        out.append(Proposal(realise("tailgate", rng, **words), "add_vehicle", "tailgate", False, anchor.object_id))
    return out


def _cones_in_lane(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    cones = _assets(facts, "static", ("traffic cone",))
    if not cones:
        return []
    out = []
    for d in _distances(facts, 15.0, INSERT_MAX_M, ("ego_lane",), rng, plain=True):
        words = {"R": row_phrase(cones[int(rng.integers(len(cones)))], int(rng.integers(3, 6)), rng),
                 "d": distance_phrase(d, rng)}
        out.append(Proposal(realise("cones_in_lane", rng, **words), "add_static", "cones_in_lane", True))
    return out


def _obstacle_in_lane(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    ds = _distances(facts, 15.0, INSERT_MAX_M, ("ego_lane",), rng, plain=True)
    return _inserts("obstacle_in_lane", facts, rng, "add_static", ds, _assets(facts, "static"), True)


def _cones_side_lane(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    cones = _assets(facts, "static", ("traffic cone",))
    out = []
    for side in _sides(facts) if cones else []:
        for d in _distances(facts, 15.0, INSERT_MAX_M, (f"{side}_lane",), rng, plain=True)[:1]:
            words = {"R": row_phrase(cones[int(rng.integers(len(cones)))], int(rng.integers(3, 6)), rng),
                     "d": distance_phrase(d, rng), "side": side}
            out.append(Proposal(realise("cones_side_lane", rng, **words), "add_static", "cones_side_lane", False))
    return out


def _static_on_road(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    ds = _distances(facts, 15.0, INSERT_MAX_M, ("ego_lane", "road"), rng, plain=True, clear_m=SMALL_SPOT_CLEAR_M)
    return _inserts("static_on_road", facts, rng, "add_static", ds, _assets(facts, "static"), False)


def _static_by_vehicle(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    assets = _assets(facts, "static")
    if not assets:
        return []
    anchors = _visible_targets(facts, "vehicle", lambda a: not a.moving and min(a.room_ahead_m, a.room_behind_m) >= 5.0)
    out = []
    for anchor, phrase in _named(facts, anchors, rng):
        words = {"A": asset_phrase(assets[int(rng.integers(len(assets)))], rng), "T": phrase}
        out.append(Proposal(realise("static_by_vehicle", rng, **words), "add_static", "static_by_vehicle", False,
                            anchor.object_id))
    return out


def _walker_kind(kind: str, safety: bool, plain: bool, lo: float) -> Builder:
    def build(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
        if kind == "sidewalk_walker" and not facts.road.sidewalks:
            return []
        areas = ("sidewalk",) if kind == "sidewalk_walker" else ("crosswalk", "road", "ego_lane")
        ds = _distances(facts, lo, INSERT_MAX_M, areas, rng, plain=plain, clear_m=SMALL_SPOT_CLEAR_M)
        return _inserts(kind, facts, rng, "add_pedestrian", ds, _assets(facts, "pedestrian"), safety)
    return build


def _crosswalk_walker(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    ahead = facts.road.crosswalk_ahead_m
    if ahead is None or ahead > INSERT_MAX_M:
        return []
    return _inserts("crosswalk_walker", facts, rng, "add_pedestrian", [ahead], _assets(facts, "pedestrian"), False)


def _modify_kind(kind: str, category: str, safety: bool, agent_kind: str, ok: Callable[[AgentFacts], bool],
                 slots: Callable[[AgentFacts, np.random.Generator], dict[str, str]] | None = None) -> Builder:
    """Builder of a kind acting on every visible, nameable object of ``agent_kind`` that passes ``ok``."""
    def build(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
        out = []
        for agent, phrase in _named(facts, _visible_targets(facts, agent_kind, ok), rng):
            extra = slots(agent, rng) if slots is not None else {}
            out.append(Proposal(realise(kind, rng, T=phrase, **extra), category, kind, safety, agent.object_id))
        return out
    return build


def _replace(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    assets = _assets(facts, "vehicle")
    if not assets:
        return []
    out = []
    for agent, phrase in _named(facts, _visible_targets(facts, "vehicle", lambda a: True), rng):
        options = [a for a in assets if a.caption != agent.caption] or list(assets)
        words = {"T": phrase, "A": asset_phrase(options[int(rng.integers(len(options)))], rng)}
        out.append(Proposal(realise("replace", rng, **words), "modify_vehicle", "replace", False, agent.object_id))
    return out


def _remove(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    out = []
    for kind in ("vehicle", "pedestrian", "static"):
        for agent, phrase in _named(facts, _visible_targets(facts, kind, lambda a: True), rng):
            out.append(Proposal(realise("remove", rng, T=phrase), "remove", "remove", False, agent.object_id))
    order = rng.permutation(len(out))
    return [out[i] for i in order]


def _remove_group(facts: SceneFacts, rng: np.random.Generator) -> list[Proposal]:
    out, seen = [], set()
    for agent in _visible_targets(facts, "static", lambda a: bool(a.caption)):
        if agent.caption in seen or not lookalikes(agent, facts):
            continue
        seen.add(agent.caption)
        out.append(Proposal(realise("remove_group", rng, G=group_phrase(agent, rng)), "remove", "remove_group", False,
                            agent.object_id))
    return out


def _on_sidewalk(a: AgentFacts) -> bool:
    return (a.area == "sidewalk" or a.context == voc.ON_THE_SIDEWALK) and a.motion not in (
        voc.CROSSING, voc.CROSSING_LEFT_TO_RIGHT, voc.CROSSING_RIGHT_TO_LEFT)


def _side_slot(a: AgentFacts, rng: np.random.Generator) -> dict[str, str]:
    return {"side": pick(rng, a.lane_change_sides)}


def _turn_slot(a: AgentFacts, rng: np.random.Generator) -> dict[str, str]:
    return {"side": pick(rng, a.turns)}


def _faster_slot(a: AgentFacts, rng: np.random.Generator) -> dict[str, str]:
    return {"v": speed_phrase(1.5 * a.speed_mps, rng)}


def _delay_slot(a: AgentFacts, rng: np.random.Generator) -> dict[str, str]:
    return {"t": duration_phrase(float(rng.integers(1, 3)), rng)}


def _moving_vehicle(a: AgentFacts) -> bool:
    return a.moving and a.speed_mps >= MIN_MOVING_MPS


#: Every proposal kind, by category (module docstring).
KINDS: tuple[ProposalKind, ...] = (
    ProposalKind("cut_in", "add_vehicle", True, _cut_in),
    ProposalKind("lead_brake", "add_vehicle", True, _lead_brake),
    ProposalKind("oncoming", "add_vehicle", False, _oncoming),
    ProposalKind("side_lane_fast", "add_vehicle", False, _side_lane_fast),
    ProposalKind("tailgate", "add_vehicle", False, _tailgate),
    ProposalKind("cones_in_lane", "add_static", True, _cones_in_lane),
    ProposalKind("obstacle_in_lane", "add_static", True, _obstacle_in_lane),
    ProposalKind("cones_side_lane", "add_static", False, _cones_side_lane),
    ProposalKind("static_on_road", "add_static", False, _static_on_road),
    ProposalKind("static_by_vehicle", "add_static", False, _static_by_vehicle),
    ProposalKind("jaywalker", "add_pedestrian", True, _walker_kind("jaywalker", True, True, 15.0)),
    ProposalKind("runner", "add_pedestrian", True, _walker_kind("runner", True, True, 15.0)),
    ProposalKind("crosswalk_walker", "add_pedestrian", False, _crosswalk_walker),
    ProposalKind("sidewalk_walker", "add_pedestrian", False, _walker_kind("sidewalk_walker", False, False, 10.0)),
    ProposalKind("hard_stop", "modify_vehicle", True,
                 _modify_kind("hard_stop", "modify_vehicle", True, "vehicle", _moving_vehicle)),
    ProposalKind("lane_change", "modify_vehicle", True,
                 _modify_kind("lane_change", "modify_vehicle", True, "vehicle",
                              lambda a: _moving_vehicle(a) and bool(a.lane_change_sides), _side_slot)),
    ProposalKind("reverse", "modify_vehicle", True,
                 _modify_kind("reverse", "modify_vehicle", True, "vehicle",
                              lambda a: not a.moving and a.room_behind_m >= REVERSE_ROOM_M)),
    ProposalKind("pull_out", "modify_vehicle", True,
                 _modify_kind("pull_out", "modify_vehicle", True, "vehicle",
                              lambda a: not a.moving and a.room_ahead_m >= PULL_OUT_ROOM_M)),
    ProposalKind("speed_up", "modify_vehicle", False,
                 _modify_kind("speed_up", "modify_vehicle", False, "vehicle",
                              lambda a: _moving_vehicle(a) and a.room_ahead_m >= SPEED_UP_ROOM_M, _faster_slot)),
    ProposalKind("slow_down", "modify_vehicle", False,
                 _modify_kind("slow_down", "modify_vehicle", False, "vehicle", _moving_vehicle)),
    ProposalKind("turn", "modify_vehicle", False,
                 _modify_kind("turn", "modify_vehicle", False, "vehicle", lambda a: bool(a.turns), _turn_slot)),
    ProposalKind("delay", "modify_vehicle", False,
                 _modify_kind("delay", "modify_vehicle", False, "vehicle",
                              lambda a: _moving_vehicle(a) and a.room_ahead_m >= DELAY_ROOM_M, _delay_slot)),
    ProposalKind("replace", "modify_vehicle", False, _replace),
    ProposalKind("ped_jaywalk", "modify_pedestrian", True,
                 _modify_kind("ped_jaywalk", "modify_pedestrian", True, "pedestrian", _on_sidewalk)),
    ProposalKind("ped_run_across", "modify_pedestrian", True,
                 _modify_kind("ped_run_across", "modify_pedestrian", True, "pedestrian", _on_sidewalk)),
    ProposalKind("ped_cross", "modify_pedestrian", False,
                 _modify_kind("ped_cross", "modify_pedestrian", False, "pedestrian", _on_sidewalk)),
    ProposalKind("ped_run", "modify_pedestrian", False,
                 _modify_kind("ped_run", "modify_pedestrian", False, "pedestrian",
                              lambda a: a.moving and a.motion != voc.STANDING)),
    ProposalKind("ped_stop", "modify_pedestrian", True,
                 _modify_kind("ped_stop", "modify_pedestrian", True, "pedestrian",
                              lambda a: a.moving and a.area in ("crosswalk", "road", "ego_lane", "intersection"))),
    ProposalKind("ped_wait", "modify_pedestrian", False,
                 _modify_kind("ped_wait", "modify_pedestrian", False, "pedestrian", lambda a: a.moving, _delay_slot)),
    ProposalKind("remove", "remove", False, _remove),
    ProposalKind("remove_group", "remove", False, _remove_group),
)


# ---------------------------------------------------------------------------------------------- selection
def proposal_rng(seed: int, seq_id: str) -> np.random.Generator:
    """The generator of one scene's proposals: ``seed`` and the scene, so scenes differ for one seed."""
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, zlib.crc32(seq_id.encode("utf-8"))])


def candidates(facts: SceneFacts, rng: np.random.Generator) -> dict[str, list[tuple[ProposalKind, list[Proposal]]]]:
    """Per category, its kinds with feasible instances, in pick order: safety-critical kinds first, each group
    in a seeded order."""
    out: dict[str, list[tuple[ProposalKind, list[Proposal]]]] = {}
    for category in EDIT_CATEGORIES:
        kinds = [k for k in KINDS if k.category == category]
        kinds = [kinds[i] for i in rng.permutation(len(kinds))]
        kinds.sort(key=lambda k: not k.safety_critical)  # stable: the seeded order within each group
        built = [(k, k.build(facts, rng)) for k in kinds]
        out[category] = [(k, found) for k, found in built if found]
    return out


def _take(found: list[Proposal], used: set[str]) -> Proposal:
    """The first proposal acting on an object not yet ``used`` (else the first), removed from ``found``."""
    index = next((i for i, p in enumerate(found) if p.target_id is None or p.target_id not in used), 0)
    return found.pop(index)


def selected_categories(categories: Iterable[str] = ()) -> tuple[str, ...]:
    """``categories`` checked against :data:`EDIT_CATEGORIES` (empty: every category), in the given order.

    Raises:
        ValueError: an unknown category (named, with the known ones).
    """
    chosen = tuple(categories)
    unknown = [c for c in chosen if c not in EDIT_CATEGORIES]
    if unknown:
        raise ValueError(f"unknown edit categor{'y' if len(unknown) == 1 else 'ies'} {unknown}: choose from "
                         f"{list(EDIT_CATEGORIES)}")
    return chosen or EDIT_CATEGORIES


def category_order(seed: int, offset: int, categories: Iterable[str] = ()) -> list[str]:
    """The run's order of the edit categories: a permutation seeded by ``seed`` alone (the same for every
    sequence of a run), less the categories not in ``categories`` (empty: keep all), rotated to start at ``offset``
    (mod the number kept)."""
    keep = set(selected_categories(categories))
    base = [EDIT_CATEGORIES[i] for i in np.random.default_rng(int(seed) & 0xFFFFFFFF).permutation(len(EDIT_CATEGORIES))]
    base = [c for c in base if c in keep]
    k = int(offset) % len(base)
    return base[k:] + base[:k]


def propose_edits(facts: SceneFacts, count: int, seed: int = 0, category_offset: int | None = None,
                  categories: Iterable[str] = ()) -> list[Proposal]:
    """Up to ``count`` distinct proposals for the scene (module docstring), deterministic for ``seed``.

    The categories come in a seeded order of the scene (``category_offset`` ``None``), or, given
    ``category_offset``, in the run's order from there (:func:`category_order`): a run gives its ``i``-th sequence
    ``i * K`` (K scenarios per sequence), so that its sequences take the categories in turn instead of each
    drawing its own order (with two sequences and K = 3, independent orders leave a category out 19 times in 20).
    ``categories`` keeps only those edit categories (empty: all six); the order of the kept ones is unchanged.

    Raises:
        ValueError: ``count < 1``, or an unknown category.
    """
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    keep = set(selected_categories(categories))
    rng = proposal_rng(seed, facts.seq_id)
    pools = {c: deque(kinds) for c, kinds in candidates(facts, rng).items() if c in keep}
    order = (category_order(seed, category_offset, categories) if category_offset is not None
             else [c for c in (EDIT_CATEGORIES[i] for i in rng.permutation(len(EDIT_CATEGORIES))) if c in keep])
    picked: list[Proposal] = []
    seen: set[str] = set()
    used: set[str] = set()
    while len(picked) < count and any(pools.values()):
        for category in order:
            queue = pools[category]
            while queue and len(picked) < count:
                kind, found = queue.popleft()
                proposal = _take(found, used)
                if found:
                    queue.append((kind, found))
                key = " ".join(proposal.prompt.lower().split())
                if key in seen:
                    continue
                seen.add(key)
                picked.append(proposal)
                if proposal.target_id is not None:
                    used.add(proposal.target_id)
                break
    logger.debug("%s: %d proposal(s) (%s)", facts.seq_id, len(picked), ", ".join(p.kind for p in picked))
    return picked


__all__ = ["EDIT_CATEGORIES", "KINDS", "Proposal", "ProposalKind", "candidates", "category_order", "propose_edits",
           "proposal_rng", "selected_categories"]
