"""Candidate edits of one synthetic scene, chosen from its ground truth so that each is well posed.

Every planner returns :class:`Draft` s -- an intent kind (a ``wording.FORMS`` key), the edit in
ground-truth terms and the phrases that fill the sentence forms -- for one category of SIMSplat Table 3
or for the infeasible set. A feasible draft is one a competent editor can carry out within the log's span
(4 s), judged from the world itself:

* targets and anchors are well visible (``truth.well_visible``) and have a description that singles them
  out (``references.py``);
* motion edits suit the target's state: speeds and stops for moving vehicles with room to brake; turns
  for vehicles approaching the junction in a lane that has the turn, close enough to make it before the
  log ends; lane changes where a lane of the same direction lies on that side and the arm is long enough;
  reversing for standing vehicles with free road behind; crossing the street for people standing or
  walking near the kerb (by a crosswalk, or away from one to jaywalk);
* the asked motion runs into no traffic replaying its log (speed-ups, turns, lane changes, inserted cars
  driving at a speed): an editor that keeps its distance would otherwise rightly not do it; a speed-up or an
  inserted car driving at a speed also keeps the editor's following gap (``FOLLOW_GAP_M`` plus its time
  headway at that speed) free ahead, since a car held back by a slower leader cannot hold the asked speed;
* insert spots are free of every agent at the first frame.

Infeasible drafts are requests the editor must refuse: an object that is not in the scene ("the purple bus"), a car
on the sidewalk, a turn for a vehicle driving away from the only junction, a lane change for a
pedestrian, motion for a static object, requests that are no edit at all.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.editing.commands import SPEED_UNITS
from simsplat_core.editing.motion.requests import FOLLOW_GAP_M, VehicleMotionRequest
from simsplat_core.eval.editing.intents import (
    EGO,
    AssetIntent,
    EditIntent,
    MotionIntent,
    PlacementIntent,
    SpeedWords,
)
from simsplat_core.eval.editing.observation import AssetLook
from simsplat_core.eval.editing.references import (
    absent_pedestrian_phrase,
    absent_vehicle_phrase,
    group_phrases,
    object_phrase,
    static_groups,
    static_phrase,
)
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.eval.editing.wording import (
    PEDESTRIAN_RELATIVE_SPEEDS,
    VEHICLE_RELATIVE_SPEEDS,
    count_word,
    distance_phrase,
    indefinite,
    person_phrase,
    pick,
    seconds_phrase,
    speed_words,
)
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.geometry import footprints_overlap
from simsplat_core.scenario.path import Path
from simsplat_core.world.agents import EGO_SIZE, Agent
from simsplat_core.world.paths import route
from simsplat_core.world.road import SIDEWALK, connector_points, target_lane

#: Comfortable deceleration used to judge whether a stop is reachable (m/s^2).
COMFORT_DECEL = 3.5
#: Footprints (length, width) of the objects a spot must have room for: a car and a traffic cone.
CAR_FOOTPRINT = (5.5, 2.2)
CONE_FOOTPRINT = (0.6, 0.6)
PERSON_FOOTPRINT = (0.8, 0.8)
#: Clearance an asked motion keeps from traffic replaying its log (metres around the box).
CLEARANCE_M = 1.0

_TURNING = (voc.TURNING_LEFT, voc.TURNING_RIGHT)
_STATIONARY = (voc.STOPPED, voc.PARKED)
_CRUISING = (voc.GOING_STRAIGHT, voc.CHANGING_LANE_LEFT, voc.CHANGING_LANE_RIGHT)
_VEHICLE_NOUNS: dict[str, tuple[str, ...]] = {
    "sedan": ("sedan",), "hatchback": ("hatchback",), "SUV": ("SUV",), "van": ("van",),
    "pickup truck": ("pickup truck", "pickup"), "truck": ("truck", "box truck"), "bus": ("bus",),
}
_CAR_LIKE = ("sedan", "hatchback", "SUV")
#: Static assets asked for: ``(subtype, colour or None, nouns)``.
STATIC_ASSETS: tuple[tuple[str, str | None, tuple[str, ...]], ...] = (
    ("traffic cone", "orange", ("traffic cone", "orange traffic cone", "orange cone", "cone")),
    ("traffic cone", "orange", ("traffic cone", "cone")),
    ("barrier", None, ("barrier", "road barrier", "construction barrier")),
    ("barrier", "white", ("white barrier", "white road barrier")),
    ("barrel", "orange", ("orange barrel", "traffic barrel", "construction barrel")),
    ("barrel", "yellow", ("yellow barrel", "yellow traffic drum")),
    ("road work sign", "orange", ("road work sign", "orange construction sign")),
)


@dataclass(frozen=True)
class Draft:
    """A candidate prompt before its sentence form is chosen.

    Attributes:
        kind: ``wording.FORMS`` key.
        intent: the edit in ground-truth terms (a form without ``{d}`` drops ``placement.distance_m``).
        slots: phrases for the forms' slots.
    """

    kind: str
    intent: EditIntent
    slots: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class AssetPools:
    """What the asset bank can be asked for: ``(subtype, colour)`` of vehicles and ``(upper, lower)`` clothing
    of pedestrians -- those of the bank (:meth:`from_bank`), or those seen well in the evaluated scenes, which
    the bank cuts its assets out of (:meth:`from_truths`). A quarter of the vehicles asked for are recoloured
    within their kind's catalogue colours (the bank makes colour variants)."""

    vehicles: tuple[tuple[str, str], ...]
    pedestrians: tuple[tuple[str, str], ...]

    @classmethod
    def from_truths(cls, truths: Sequence[SceneTruth]) -> AssetPools:
        vehicles, pedestrians = set(), set()
        for truth in truths:
            for agent in truth.world.agents:
                if not truth.well_visible(agent.object_id):
                    continue
                if agent.category == "vehicle":
                    vehicles.add((agent.subtype, agent.appearance["color"]))
                elif agent.category == "pedestrian":
                    pedestrians.add((agent.appearance["upper_color"], agent.appearance["lower_color"]))
        if not vehicles or not pedestrians:
            raise ValueError("no well-visible vehicle or pedestrian in the scenes: nothing to build assets from")
        return cls(tuple(sorted(vehicles)), tuple(sorted(pedestrians)))

    @classmethod
    def from_bank(cls, assets: Sequence[AssetLook]) -> AssetPools:
        """What an asset bank holds (``AssetLook.of_asset`` of its assets): the looks its vehicles and
        pedestrians have (pedestrians with known trousers)."""
        vehicles = {(a.subtype, a.color) for a in assets if a.category == "vehicle"}
        pedestrians = {(a.color, a.lower) for a in assets if a.category == "pedestrian" and a.lower}
        if not vehicles or not pedestrians:
            raise ValueError("the asset bank has no vehicle or no pedestrian (with known clothing colours)")
        return cls(tuple(sorted(vehicles)), tuple(sorted((u, lo) for u, lo in pedestrians if lo is not None)))


# ---------------------------------------------------------------------------------------------- helpers
def _span(truth: SceneTruth) -> float:
    """Seconds the log lasts: edits must show within them."""
    return float(truth.world.times[-1] - truth.world.times[0])


def _speed0(agent: Agent) -> float:
    return float(agent.traj["speed"][0])


def _label(truth: SceneTruth, object_id: str) -> str | None:
    return truth.facts[object_id].motion


class _Namer:
    """Fresh words for one object at every call (the description family and wording vary)."""

    def __init__(self, truth: SceneTruth, agent: Agent, rng: np.random.Generator) -> None:
        self.truth, self.agent, self.rng = truth, agent, rng

    def __call__(self) -> str:
        if self.agent.category in ("vehicle", "pedestrian"):
            phrase = object_phrase(self.truth, self.agent.object_id, self.rng)
        else:
            phrase = static_phrase(self.truth, self.agent.object_id, self.rng)
        assert phrase is not None  # _named only keeps objects that have one
        return phrase


def _named(truth: SceneTruth, rng: np.random.Generator, kinds: tuple[str, ...]) -> list[tuple[Agent, _Namer]]:
    """Well-visible agents of ``kinds`` with a description that singles them out, and their namers."""
    out = []
    for agent in truth.world.agents:
        if agent.category not in kinds or not truth.well_visible(agent.object_id):
            continue
        phrase = (object_phrase(truth, agent.object_id, rng) if agent.category in ("vehicle", "pedestrian")
                  else static_phrase(truth, agent.object_id, rng))
        if phrase is not None:
            out.append((agent, _Namer(truth, agent, rng)))
    return out


def _free(truth: SceneTruth, xy: np.ndarray, heading: float, size: tuple[float, float] = CAR_FOOTPRINT,
          margin: float = 1.0, skip: str = "", frame: int = 0) -> bool:
    """A box of ``size`` at ``xy`` facing ``heading``, grown by ``margin``, overlaps neither the ego nor any agent
    (but ``skip``) at ``frame``."""
    boxes = [(truth.ego_xy[frame], float(truth.ego_heading[frame]), EGO_SIZE[:2])]
    boxes += [(a.traj["xy"][frame], float(a.traj["heading"][frame]), a.size[:2]) for a in truth.world.agents
              if a.object_id != skip]
    return not any(footprints_overlap(np.asarray(xy, float)[None], np.array([heading]), size, np.asarray(c)[None],
                                      np.array([h]), (float(sz[0]), float(sz[1])), margin)[0] for c, h, sz in boxes)


#: Metres from one cone of a row to the next (the editor's row spacing between boxes plus a cone's length).
ROW_STEP_M = 1.5 + CONE_FOOTPRINT[0]


def _row_free(truth: SceneTruth, distance: float, side: int, count: int) -> bool:
    """Whether a row of ``count`` cones starting ``distance`` ahead in the ego's lane (``side`` as
    :func:`_ego_lane_spot`) and running on along it has every cone's spot free (a row reaches past its first
    cone: a car standing a few metres further leaves no room for it)."""
    for k in range(1, count):
        found = _ego_lane_spot(truth, distance + k * ROW_STEP_M, side)
        if found is None or not _free(truth, *found, size=CONE_FOOTPRINT, margin=1.5):
            return False
    return True


def _clear_run(truth: SceneTruth, path: Path, s0: float, v0: float, v1: float, size: tuple[float, ...], skip: str = "",  # noqa: PLR0913 -- the motion to test, each argument a named physical quantity
               lateral: float = 0.0, accel: float = 2.0, margin: float = CLEARANCE_M, keep_gap: bool = False) -> bool:
    """Driving ``path`` from arc length ``s0`` at ``v0`` m/s, changing to ``v1`` at ``accel`` m/s^2 (shifted
    ``lateral`` metres to the left), overlaps no agent but ``skip`` (nor the ego, ahead of it) over the log:
    the requested motion is possible without running into (or brushing past, ``margin``) traffic that replays its
    log. With ``keep_gap`` the box reaches ahead by the gap the editor's planner keeps to a leader at the faster
    speed (``FOLLOW_GAP_M`` plus its time headway): a car asked to drive at a speed can only hold it with that
    much road free ahead of it."""
    t = truth.world.times
    dv = v1 - v0
    ta = abs(dv) / accel
    a = np.sign(dv) * accel
    s = s0 + np.where(t < ta, v0 * t + 0.5 * a * t * t, v0 * ta + 0.5 * a * ta * ta + v1 * (t - ta))
    gap = FOLLOW_GAP_M + VehicleMotionRequest.headway_s * max(v0, v1) if keep_gap else 0.0
    xy, heading = path.position(s + gap / 2.0), path.heading(s + gap / 2.0)
    xy = xy + lateral * np.stack([-np.sin(heading), np.cos(heading)], axis=1)
    return _runs_clear(truth, xy, heading, (float(size[0]) + gap, float(size[1])), skip, margin)


def _runs_clear(truth: SceneTruth, xy: np.ndarray, heading: np.ndarray, foot: tuple[float, float], skip: str,
                margin: float) -> bool:
    """A box of ``foot`` at ``xy [T, 2]`` / ``heading [T]`` overlaps (grown by ``margin``) neither the ego nor any
    agent but ``skip``, step by step over their logs."""
    others = [(truth.ego_xy, truth.ego_heading, EGO_SIZE)] + [
        (o.traj["xy"], o.traj["heading"], o.size) for o in truth.world.agents if o.object_id != skip]
    return not any(footprints_overlap(xy, heading, foot, oxy, oh, (float(osz[0]), float(osz[1])), margin).any()
                   for oxy, oh, osz in others)


def _delay_clear(truth: SceneTruth, agent: Agent, delay: float) -> bool:
    """Whether ``agent`` setting off ``delay`` seconds late (standing at its start, then driving its logged
    path as logged) runs into nobody replaying the log: a car close behind it (the ego first) would run into it,
    and an editor that keeps the traffic replaying its log rightly refuses that."""
    t = truth.world.times
    late = np.interp(np.maximum(t - delay, t[0]), t, agent.traj["s"])
    path = agent.motion.path
    return _runs_clear(truth, path.position(late), path.heading(late),
                       (float(agent.size[0]), float(agent.size[1])), agent.object_id, 0.0)


def _ego_lane_spot(truth: SceneTruth, distance: float, side: int = 0) -> tuple[np.ndarray, float] | None:
    """``(world point, lane heading)`` ``distance`` ahead of the ego along its lane (``side`` lanes to the left,
    +1, or right, -1); ``None`` when that lane does not exist or ends before."""
    xy0, h0 = truth.ego_xy[0], float(truth.ego_heading[0])
    left = np.array([-np.sin(h0), np.cos(h0)])
    start = xy0 + side * truth.layout.lane_w_h * left
    if side:
        pos = truth.road_position(start, h0)
        if pos.lane is None or pos.region != "travel":
            return None
    try:
        path = truth.lanes.follow(start, h0, "straight")
    except ValueError:
        return None
    s = path.start_s + distance
    if s > path.path.length:
        return None
    return np.asarray(path.path.position(s), dtype=np.float64), float(path.path.heading(s))


def _ego_frame_point(truth: SceneTruth, ahead: float, left: float) -> np.ndarray:
    """World point ``ahead`` metres in front of and ``left`` metres left of the ego at the first frame."""
    h = float(truth.ego_heading[0])
    return truth.ego_xy[0] + ahead * np.array([np.cos(h), np.sin(h)]) + left * np.array([-np.sin(h), np.cos(h)])


def _sidewalk_ahead(truth: SceneTruth, distance: float) -> bool:
    """Some sidewalk lies ``distance`` (+-1.5 m) ahead of the ego, within 15 m to either side: "on the sidewalk
    d m ahead" has a place (ahead of the junction box there is none)."""
    pts = np.array([_ego_frame_point(truth, distance + dx, dy) for dx in np.arange(-1.5, 1.6, 0.5)
                    for dy in np.arange(-15.0, 15.1, 0.5)])
    return bool((truth.layout.region(pts) == SIDEWALK).any())


def _road_ahead(truth: SceneTruth, distance: float) -> tuple[bool, bool]:
    """``(the road straight ahead at distance is an arm's travel lanes, ... and 3 m clear of its crosswalk)``:
    where crossing (or jaywalking across) the street ``d`` m ahead is well defined."""
    pos = truth.road_position(_ego_frame_point(truth, distance, 0.0), float(truth.ego_heading[0]))
    if pos.arm is None or pos.region != "travel":
        return False, False
    c0, c1 = truth.layout.crosswalk_range(pos.arm)
    return True, abs(pos.along - 0.5 * (c0 + c1)) - 0.5 * (c1 - c0) >= 3.0


def _vehicle_asset(pools: AssetPools, rng: np.random.Generator, avoid: tuple[str, str] | None = None
                   ) -> tuple[AssetIntent, str]:
    """An asset vehicle (most from the pool, some recoloured within its kind's catalogue colours)."""
    from simsplat_core.world.palette import VEHICLE_KIND_BY_NAME  # noqa: PLC0415  # numba-heavy world package

    options = [p for p in pools.vehicles if p != avoid] or list(pools.vehicles)
    subtype, color = options[int(rng.integers(len(options)))]
    if rng.random() < 0.25:
        color = pick(rng, VEHICLE_KIND_BY_NAME[subtype].colors)
    if subtype in _CAR_LIKE and rng.random() < 0.2:
        noun, intent_subtype = "car", None
    else:
        noun, intent_subtype = pick(rng, _VEHICLE_NOUNS.get(subtype, (subtype,))), subtype
    words = indefinite(f"{color} {noun}")
    return AssetIntent("vehicle", intent_subtype, color, description=words), words


def _pedestrian_asset(pools: AssetPools, rng: np.random.Generator) -> tuple[AssetIntent, str]:
    upper, lower = pools.pedestrians[int(rng.integers(len(pools.pedestrians)))]
    both = rng.random() < 0.4
    words = person_phrase(upper, lower if both else None, rng)
    return AssetIntent("pedestrian", None, None, upper, lower if both else None, description=words), words


def _static_asset(rng: np.random.Generator, count: int = 1) -> tuple[AssetIntent, str]:
    subtype, color, nouns = STATIC_ASSETS[int(rng.integers(len(STATIC_ASSETS)))]
    noun = pick(rng, nouns)
    words = indefinite(noun)
    return AssetIntent("static", subtype, color, count=count, description=words), words


def _anchor_vehicles(truth: SceneTruth, rng: np.random.Generator) -> list[tuple[Agent, _Namer]]:
    """Named vehicles in a travel or parking lane of an arm at the first frame (not in the junction)."""
    out = []
    for agent, phrase in _named(truth, rng, ("vehicle",)):
        pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
        if pos.arm is not None and pos.region in ("travel", "parking"):
            out.append((agent, phrase))
    return out


def _spot_near(agent: Agent, along: float, across: float) -> np.ndarray:
    h = float(agent.traj["heading"][0])
    fwd, left = np.array([np.cos(h), np.sin(h)]), np.array([-np.sin(h), np.cos(h)])
    return np.asarray(agent.traj["xy"][0] + along * fwd + across * left, dtype=np.float64)


# ---------------------------------------------------------------------------------------------- add
def plan_add_vehicle(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    out: list[Draft] = []
    ego_pos = truth.road_position(truth.ego_xy[0], float(truth.ego_heading[0]))
    for distance in (10.0, 12.0, 15.0, 18.0, 20.0, 25.0, 30.0):
        found = _ego_lane_spot(truth, distance)
        if found is not None and _free(truth, *found):
            for kind in ("vehicle_lane_ahead", "vehicle_lane_speed"):
                asset, words = _vehicle_asset(pools, rng)
                motion = None
                slots = {"A": words, "d": distance_phrase(distance, rng)}
                if kind == "vehicle_lane_speed":
                    unit = pick(rng, ("km/h", "km/h", "m/s", "mph"))
                    said, value, mps = speed_words(float(rng.uniform(5.0, 11.0)), unit, rng)
                    lane = truth.lanes.follow(found[0], found[1], "straight")
                    if not _clear_run(truth, lane.path, lane.start_s, mps, mps, CAR_FOOTPRINT, keep_gap=True):
                        continue
                    motion = MotionIntent(speed_mps=mps, speed=SpeedWords("absolute", value, unit))
                    slots["v"] = said
                out.append(Draft(kind, EditIntent("insert", asset=asset, motion=motion,
                                                  placement=PlacementIntent("in_lane", EGO, distance, "same")), slots))
        for side, name in ((1, "left"), (-1, "right")):
            if ego_pos.lane is None or not 0 <= ego_pos.lane - side < truth.layout.lanes_h:
                continue
            found = _ego_lane_spot(truth, distance, side)
            if found is not None and _free(truth, *found):
                asset, words = _vehicle_asset(pools, rng)
                out.append(Draft("vehicle_side_lane", EditIntent(
                    "insert", asset=asset, placement=PlacementIntent("in_lane", EGO, distance, name)),
                    {"A": words, "d": distance_phrase(distance, rng), "side": name}))
        opposite = truth.ego_xy[0] + distance * np.array([np.cos(truth.ego_heading[0]), np.sin(truth.ego_heading[0])])
        h0 = float(truth.ego_heading[0])
        across = 2 * (ego_pos.lateral if ego_pos.lateral else 0.0)
        opposite = opposite + across * np.array([-np.sin(h0), np.cos(h0)])
        pos = truth.road_position(opposite, h0 + np.pi)
        if distance >= 15 and pos.region == "travel" and pos.lane is not None and _free(truth, opposite, h0 + np.pi):
            asset, words = _vehicle_asset(pools, rng)
            out.append(Draft("vehicle_oncoming", EditIntent(
                "insert", asset=asset, placement=PlacementIntent("in_lane", EGO, distance, "opposite")),
                {"A": words, "d": distance_phrase(distance, rng)}))
    for anchor, phrase in _anchor_vehicles(truth, rng):
        length = anchor.size[0]
        for kind, sign, relation in (("vehicle_behind_anchor", -1.0, "behind"),
                                     ("vehicle_front_anchor", 1.0, "in_front_of")):
            gap = float(pick(rng, ("5", "6", "8", "10")))
            spot = _spot_near(anchor, sign * (length / 2 + gap + 2.4), 0.0)
            pos = truth.road_position(spot, float(anchor.traj["heading"][0]))
            if pos.region not in ("travel", "parking") or not _free(truth, spot, float(anchor.traj["heading"][0])):
                continue
            asset, words = _vehicle_asset(pools, rng)
            out.append(Draft(kind, EditIntent("insert", asset=asset,
                                              placement=PlacementIntent(relation, anchor.object_id, gap)),
                             {"A": words, "anchor": phrase(), "d": distance_phrase(gap, rng)}))
    return out


def plan_add_static(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    del pools
    out: list[Draft] = []
    ego_pos = truth.road_position(truth.ego_xy[0], float(truth.ego_heading[0]))
    for distance in (8.0, 10.0, 12.0, 15.0, 20.0):
        found = _ego_lane_spot(truth, distance)
        if found is not None and _free(truth, *found, size=CONE_FOOTPRINT, margin=1.5):
            asset, words = _static_asset(rng)
            out.append(Draft("static_lane_ahead", EditIntent(
                "insert", asset=asset, placement=PlacementIntent("in_lane", EGO, distance, "same")),
                {"A": words, "d": distance_phrase(distance, rng)}))
            n = int(rng.integers(3, 6))
            asset = AssetIntent("static", "traffic cone", "orange", count=n, description=f"a row of {n} cones")
            if _row_free(truth, distance, 0, n):
                out.append(Draft("static_row", EditIntent(
                    "insert", asset=asset, placement=PlacementIntent("in_lane", EGO, distance, "same")),
                    {"n": count_word(n, rng), "items": pick(rng, ("cones", "traffic cones", "orange cones")),
                     "d": distance_phrase(distance, rng)}))
        for side, name in ((1, "left"), (-1, "right")):
            if ego_pos.lane is None or not 0 <= ego_pos.lane - side < truth.layout.lanes_h:
                continue
            found = _ego_lane_spot(truth, distance, side)
            if found is not None and _free(truth, *found, size=CONE_FOOTPRINT, margin=1.5):
                asset, words = _static_asset(rng)
                out.append(Draft("static_side_lane", EditIntent(
                    "insert", asset=asset, placement=PlacementIntent("in_lane", EGO, distance, name)),
                    {"A": words, "d": distance_phrase(distance, rng), "side": name}))
                n = int(rng.integers(3, 6))
                asset = AssetIntent("static", "traffic cone", "orange", count=n, description=f"a row of {n} cones")
                if not _row_free(truth, distance, side, n):
                    continue
                out.append(Draft("static_row_side", EditIntent(
                    "insert", asset=asset, placement=PlacementIntent("in_lane", EGO, distance, name)),
                    {"n": count_word(n, rng), "items": pick(rng, ("cones", "traffic cones", "orange cones")),
                     "d": distance_phrase(distance, rng), "side": name}))
    for distance in (10.0, 15.0, 20.0):
        if not _sidewalk_ahead(truth, distance):
            continue
        asset, words = _static_asset(rng)
        out.append(Draft("static_sidewalk", EditIntent(
            "insert", asset=asset, placement=PlacementIntent("on_sidewalk", EGO, distance)),
            {"A": words, "d": distance_phrase(distance, rng)}))
    asset, words = _static_asset(rng)
    out.append(Draft("static_crosswalk", EditIntent("insert", asset=asset,
                                                    placement=PlacementIntent("on_crosswalk", EGO)), {"A": words}))
    for anchor, phrase in _anchor_vehicles(truth, rng):
        for kind, along, relation in (("static_anchor_behind", -1.0, "behind"),
                                      ("static_anchor_front", 1.0, "in_front_of")):
            gap = float(pick(rng, ("1", "1.5", "2", "3")))
            spot = _spot_near(anchor, along * (anchor.size[0] / 2 + gap), 0.0)
            if truth.layout.on_road(spot[None])[0] and _free(truth, spot, 0.0, CONE_FOOTPRINT, 0.5, anchor.object_id):
                asset, words = _static_asset(rng)
                out.append(Draft(kind, EditIntent("insert", asset=asset,
                                                  placement=PlacementIntent(relation, anchor.object_id, gap)),
                                 {"A": words, "anchor": phrase(), "d": distance_phrase(gap, rng)}))
        for sign, name, relation in ((1.0, "left", "left_of"), (-1.0, "right", "right_of")):
            gap = float(pick(rng, ("1", "1.5", "2")))
            spot = _spot_near(anchor, 0.0, sign * (anchor.size[1] / 2 + gap))
            if truth.layout.on_road(spot[None])[0] and _free(truth, spot, 0.0, CONE_FOOTPRINT, 0.5, anchor.object_id):
                asset, words = _static_asset(rng)
                out.append(Draft("static_anchor_side", EditIntent(
                    "insert", asset=asset, placement=PlacementIntent(relation, anchor.object_id, gap)),
                    {"A": words, "anchor": phrase(), "d": distance_phrase(gap, rng), "side": name}))
    return out


def plan_add_pedestrian(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    out: list[Draft] = []
    for distance in (8.0, 10.0, 12.0, 15.0, 20.0):
        sidewalk, (road, off_crosswalk) = _sidewalk_ahead(truth, distance), _road_ahead(truth, distance)
        free = _free(truth, _ego_frame_point(truth, distance, 0.0), 0.0, PERSON_FOOTPRINT, 1.0)
        road, off_crosswalk = road and free, off_crosswalk and free
        for kind, placement, motion, feasible in (
            ("pedestrian_sidewalk", PlacementIntent("on_sidewalk", EGO, distance), None, sidewalk),
            ("pedestrian_crossing", PlacementIntent("in_front_of", EGO, distance), MotionIntent(cross_street=True),
             road),
            ("pedestrian_insert_jaywalk", PlacementIntent("in_front_of", EGO, distance),
             MotionIntent(cross_street=True, jaywalk=True), off_crosswalk),
            ("pedestrian_insert_run", PlacementIntent("on_sidewalk", EGO, distance), MotionIntent(gait="run"),
             sidewalk),
        ):
            if not feasible:
                continue
            asset, words = _pedestrian_asset(pools, rng)
            out.append(Draft(kind, EditIntent("insert", asset=asset, placement=placement, motion=motion),
                             {"A": words, "d": distance_phrase(distance, rng)}))
        if not sidewalk:
            continue
        asset, words = _pedestrian_asset(pools, rng)
        said, value, mps = speed_words(float(rng.uniform(0.8, 1.8)), "m/s", rng)
        out.append(Draft("pedestrian_walk_speed", EditIntent(
            "insert", asset=asset, placement=PlacementIntent("on_sidewalk", EGO, distance),
            motion=MotionIntent(speed_mps=mps, speed=SpeedWords("absolute", value, "m/s"))),
            {"A": words, "d": distance_phrase(distance, rng), "v": said}))
    for _ in range(2):
        asset, words = _pedestrian_asset(pools, rng)
        out.append(Draft("pedestrian_crosswalk", EditIntent("insert", asset=asset,
                                                            placement=PlacementIntent("on_crosswalk", EGO)),
                         {"A": words}))
    for anchor, phrase in _named(truth, rng, ("vehicle", "pedestrian")):
        if anchor.category == "vehicle" and _label(truth, anchor.object_id) not in _STATIONARY:
            continue  # a person stands next to a parked or waiting car, not next to one driving through
        side = pick(rng, ("left", "right"))
        gap = float(pick(rng, ("1", "1.5", "2")))
        asset, words = _pedestrian_asset(pools, rng)
        out.append(Draft("pedestrian_next_to", EditIntent(
            "insert", asset=asset, placement=PlacementIntent("next_to", anchor.object_id)),
            {"A": words, "anchor": phrase()}))
        asset, words = _pedestrian_asset(pools, rng)
        out.append(Draft("pedestrian_side_of", EditIntent(
            "insert", asset=asset, placement=PlacementIntent(f"{side}_of", anchor.object_id, gap)),
            {"A": words, "anchor": phrase(), "d": distance_phrase(gap, rng), "side": side}))
    return out


# ---------------------------------------------------------------------------------------------- modify
def _turn_reachable(truth: SceneTruth, agent: Agent, turn: str) -> bool:
    """Approaching the junction in a lane that has ``turn``, close enough to be well into it by the end."""
    pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
    v = _speed0(agent)
    if pos.arm is None or not pos.inbound or pos.lane is None or v < 3.0:
        return False
    if target_lane(truth.layout, pos.arm, pos.lane, turn) is None:
        return False
    to_stop = pos.along - truth.layout.stopline_s(pos.arm)
    conn = connector_points(truth.layout, pos.arm, pos.lane, turn)
    if conn is None or to_stop < -0.5:
        return False
    conn_len = float(np.linalg.norm(np.diff(conn, axis=0), axis=1).sum())
    return to_stop + 0.6 * conn_len <= 0.8 * v * _span(truth)


def _route_clear(truth: SceneTruth, agent: Agent, turn: str) -> bool:
    """The agent's lane route making ``turn`` at the junction, at its speed, runs into no traffic."""
    pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
    assert pos.arm is not None and pos.lane is not None  # _turn_reachable holds
    path = route(truth.layout, pos.arm, pos.lane, turn)
    v0 = _speed0(agent)
    return _clear_run(truth, path, path.project(agent.traj["xy"][0]), v0, v0, agent.size, agent.object_id)


def _lane_change_room(truth: SceneTruth, agent: Agent, side: str) -> bool:
    pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
    v = _speed0(agent)
    if pos.arm is None or pos.lane is None or pos.region != "travel" or v < 4.0:
        return False
    new_lane = pos.lane - 1 if side == "left" else pos.lane + 1
    if not 0 <= new_lane < truth.layout.lanes(pos.arm):
        return False
    if pos.inbound:
        return pos.along - truth.layout.stopline_s(pos.arm) >= v * 3.5 + 5.0
    return pos.along + v * _span(truth) < truth.layout.arm_length


def _crosswalk_stop_room(truth: SceneTruth, agent: Agent) -> bool:
    pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
    v = _speed0(agent)
    if pos.arm is None or not pos.inbound or v < 3.0:
        return False
    front_to_crosswalk = pos.along - agent.size[0] / 2 - truth.layout.crosswalk_range(pos.arm)[1]
    # room to brake comfortably, and close enough that braking all the way ends within the log
    return v * v / (2 * COMFORT_DECEL) + 1.0 <= front_to_crosswalk <= v * _span(truth) / 2


def _room_behind(truth: SceneTruth, agent: Agent, metres: float = 8.0) -> bool:
    spot = _spot_near(agent, -(agent.size[0] / 2 + metres / 2), 0.0)
    if not truth.layout.on_road(spot[None])[0]:
        return False
    for frame in range(0, truth.log.num_frames, 5):
        centres = [truth.ego_xy[frame]] + [a.traj["xy"][frame] for a in truth.world.agents
                                          if a.object_id != agent.object_id]
        if np.min(np.linalg.norm(np.asarray(centres) - spot, axis=1)) < metres / 2 + EGO_SIZE[0] / 2:
            return False
    return True


#: Drafts of one kind, before the kind is attached: ``(intent, slots)`` pairs.
Drafted = list[tuple[EditIntent, dict[str, str]]]


@dataclass(frozen=True)
class _Subject:
    """A named agent the drafters write prompts about: the scene, the agent, its namer and the slots its modify
    drafts share (``{"T": its words}``, drawn once per agent; empty for the infeasible drafters, which name it
    themselves)."""

    truth: SceneTruth
    agent: Agent
    namer: _Namer
    slot: dict[str, str]

    @property
    def oid(self) -> str:
        return self.agent.object_id

    @property
    def v0(self) -> float:
        """Speed at the first frame, m/s."""
        return _speed0(self.agent)

    @property
    def label(self) -> str | None:
        """The auto-labeller's motion class of the agent's log."""
        return _label(self.truth, self.agent.object_id)

    def modify(self, motion: MotionIntent, **slots: str) -> Drafted:
        """One draft modifying the agent to ``motion``, with the shared slots and ``slots``."""
        return [(EditIntent("modify", (self.oid,), motion=motion), {**self.slot, **slots})]


#: A drafter of one intent kind: ``(subject, pools, rng) ->`` its ``(intent, slots)`` drafts about the subject (none
#: when the subject's state does not suit the kind). Drafters draw from ``rng`` in their table's order.
Drafter = Callable[[_Subject, AssetPools, np.random.Generator], Drafted]


def _moving(s: _Subject) -> bool:
    return s.v0 >= 3.0


def _clear_own(s: _Subject, v1: float) -> bool:
    """Driving its own path at ``v1`` (from its speed) stays clear of traffic: faster it may run into the car ahead
    (or come closer to it than the editor's following gap), slower it may meet crossing traffic it passed before."""
    a = s.agent
    return _clear_run(s.truth, a.motion.path, float(a.traj["s"][0]), s.v0, v1, a.size, a.object_id, keep_gap=v1 > s.v0)


def _vehicle_speed_abs(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if not (_moving(s) and s.label in _CRUISING):
        return []
    v0 = s.v0
    unit = pick(rng, ("km/h", "m/s", "mph", "km/h"))
    delta = float(rng.uniform(2.5, 5.5)) * (1 if rng.random() < 0.5 or v0 < 6.5 else -1)
    words, value, mps = speed_words(v0 + delta, unit, rng)
    if abs(mps - v0) >= 2.0 and mps >= 3.0 and _clear_own(s, mps):
        return s.modify(MotionIntent(speed_mps=mps, speed=SpeedWords("absolute", value, unit)), v=words)
    return []


def _vehicle_speed_rel(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    steady = float(np.std(s.agent.traj["speed"])) < 0.3
    if not (_moving(s) and steady and s.label in _CRUISING):
        return []
    v0 = s.v0
    rel, mode, value, unit = VEHICLE_RELATIVE_SPEEDS[int(rng.integers(len(VEHICLE_RELATIVE_SPEEDS)))]
    target = v0 * value if mode == "factor" else v0 + value * SPEED_UNITS[unit]
    if 1.5 <= target <= 17.0 and abs(target - v0) <= 7.5 and _clear_own(s, target):
        return s.modify(MotionIntent(speed_mps=target, speed=SpeedWords(mode, value, unit)), rel=rel)
    return []


def _may_slow(s: _Subject) -> bool:
    """Moving, and not slowing down or stopping already."""
    return _moving(s) and s.label not in (voc.STOPPING, voc.SLOWING_DOWN)


def _vehicle_stop_crosswalk(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if _may_slow(s) and _crosswalk_stop_room(s.truth, s.agent):
        return s.modify(MotionIntent(stop=True, stop_before="crosswalk"))
    return []


def _vehicle_stop(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if _may_slow(s) and s.v0 / COMFORT_DECEL <= _span(s.truth) - 1.0:  # a comfortable stop ends within the log
        return s.modify(MotionIntent(stop=True))
    return []


def _vehicle_stop_by(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if not _may_slow(s):
        return []
    by = float(pick(rng, ("2", "2.5", "3")))
    if s.v0 / by <= 4.5:
        return s.modify(MotionIntent(stop=True, stop_by_s=by), t=seconds_phrase(by, rng))
    return []


def _vehicle_brake_hard(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    return s.modify(MotionIntent(longitudinal="brake_hard")) if _may_slow(s) else []


def _vehicle_decelerate(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    return s.modify(MotionIntent(longitudinal="decelerate")) if _may_slow(s) else []


def _vehicle_accelerate(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if _moving(s) and s.label not in (voc.SPEEDING_UP, *_TURNING) and s.v0 <= 12.0 and _clear_own(s, s.v0 + 3.0):
        return s.modify(MotionIntent(longitudinal="accelerate"))
    return []


def _vehicle_reverse(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if s.label in _STATIONARY and _room_behind(s.truth, s.agent):
        return s.modify(MotionIntent(reverse=True))
    return []


def _vehicle_lane_change(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if s.label in (voc.CHANGING_LANE_LEFT, voc.CHANGING_LANE_RIGHT, *_TURNING):
        return []
    a, out = s.agent, []
    for side in ("left", "right"):
        width = s.truth.layout.lane_w_h * (1 if side == "left" else -1)
        if _lane_change_room(s.truth, a, side) and _clear_run(s.truth, a.motion.path, float(a.traj["s"][0]), s.v0,
                                                              s.v0, a.size, s.oid, lateral=width):
            out += s.modify(MotionIntent(lane_change=side), side=side)
    return out


def _vehicle_turn(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    out = []
    for turn in ("left", "right"):
        if s.label != f"turning_{turn}" and _turn_reachable(s.truth, s.agent, turn) and _route_clear(s.truth, s.agent,
                                                                                                     turn):
            out += s.modify(MotionIntent(turn=turn), side=turn)
    return out


def _vehicle_straight(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if s.label in _TURNING and _turn_reachable(s.truth, s.agent, "straight") and _route_clear(s.truth, s.agent,
                                                                                              "straight"):
        return s.modify(MotionIntent(turn="straight"))
    return []


def _vehicle_delay(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if not _moving(s):
        return []
    delay = float(pick(rng, ("1", "1.5", "2")))
    if _delay_clear(s.truth, s.agent, delay):
        return s.modify(MotionIntent(delay_s=delay), t=seconds_phrase(delay, rng))
    return []


def _vehicle_replace(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    asset, words = _vehicle_asset(pools, rng, avoid=(s.agent.subtype, s.agent.appearance["color"]))
    return [(EditIntent("replace", (s.oid,), asset=asset), {**s.slot, "A": words})]


#: The modify_vehicle drafters, by intent kind, in the order they run for each named vehicle.
VEHICLE_DRAFTERS: tuple[tuple[str, Drafter], ...] = (
    ("vehicle_speed_abs", _vehicle_speed_abs), ("vehicle_speed_rel", _vehicle_speed_rel),
    ("vehicle_stop_crosswalk", _vehicle_stop_crosswalk), ("vehicle_stop", _vehicle_stop),
    ("vehicle_stop_by", _vehicle_stop_by), ("vehicle_brake_hard", _vehicle_brake_hard),
    ("vehicle_decelerate", _vehicle_decelerate), ("vehicle_accelerate", _vehicle_accelerate),
    ("vehicle_reverse", _vehicle_reverse), ("vehicle_lane_change", _vehicle_lane_change),
    ("vehicle_turn", _vehicle_turn), ("vehicle_straight", _vehicle_straight), ("vehicle_delay", _vehicle_delay),
    ("vehicle_replace", _vehicle_replace),
)


def _drafts(subject: _Subject, drafters: tuple[tuple[str, Drafter], ...], pools: AssetPools,
            rng: np.random.Generator) -> list[Draft]:
    """The drafts of every drafter about ``subject``, in the drafters' order, each of its drafter's kind."""
    return [Draft(kind, intent, slots) for kind, drafter in drafters for intent, slots in drafter(subject, pools, rng)]


def plan_modify_vehicle(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    """Every :data:`VEHICLE_DRAFTERS` draft about every named vehicle."""
    return [d for agent, namer in _named(truth, rng, ("vehicle",))
            for d in _drafts(_Subject(truth, agent, namer, {"T": namer()}), VEHICLE_DRAFTERS, pools, rng)]


def _near_kerb(truth: SceneTruth, agent: Agent) -> tuple[bool, bool]:
    """``(on a sidewalk within 2.5 m of the kerb by a crosswalk, ... away from the crosswalks)`` at the first
    frame: where "cross the street" means crossing now, on the crosswalk or (jaywalking) off it."""
    pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
    if pos.arm is None or pos.region != "sidewalk":
        return False, False
    near = abs(pos.lateral) - truth.layout.half_width(pos.arm) <= 2.5
    c0, c1 = truth.layout.crosswalk_range(pos.arm)
    off = abs(pos.along - 0.5 * (c0 + c1)) - 0.5 * (c1 - c0)
    return near and off <= 3.0, near and off >= 3.0


def _walking_throughout(s: _Subject) -> bool:
    return s.v0 >= 0.8 and float(np.mean(s.agent.traj["speed"] >= 0.8)) >= 0.6


def _pedestrian_speed_abs(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if not _walking_throughout(s):
        return []
    target = float(pick(rng, ("0.6", "0.8", "2", "2.5")))
    unit = "km/h" if rng.random() < 0.3 else "m/s"
    if unit == "km/h":
        kmh = float(pick(rng, ("3", "7", "8")))
        words, value, mps = f"{kmh:g} km/h", kmh, kmh / 3.6
    else:
        words, value, mps = speed_words(target, "m/s", rng)
    if abs(mps - s.v0) >= 0.4:
        return s.modify(MotionIntent(speed_mps=mps, speed=SpeedWords("absolute", value, unit)), v=words)
    return []


def _pedestrian_speed_rel(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if not _walking_throughout(s):
        return []
    rel, mode, factor, unit = PEDESTRIAN_RELATIVE_SPEEDS[int(rng.integers(len(PEDESTRIAN_RELATIVE_SPEEDS)))]
    return s.modify(MotionIntent(speed_mps=s.v0 * factor, speed=SpeedWords(mode, factor, unit)), rel=rel)


def _pedestrian_run(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    return s.modify(MotionIntent(gait="run")) if _walking_throughout(s) else []


def _pedestrian_stop(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    return s.modify(MotionIntent(stop=True)) if _walking_throughout(s) else []


def _pedestrian_delay(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    if not _walking_throughout(s):
        return []
    delay = float(pick(rng, ("1", "1.5", "2")))
    return s.modify(MotionIntent(delay_s=delay), t=seconds_phrase(delay, rng))


def _kerb_side(s: _Subject) -> tuple[bool, bool]:
    """:func:`_near_kerb` of a standing or walking subject (``(False, False)`` for others)."""
    return _near_kerb(s.truth, s.agent) if s.label in (voc.STANDING, voc.WALKING_ALONG) else (False, False)


def _pedestrian_cross(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    return s.modify(MotionIntent(cross_street=True)) if _kerb_side(s)[0] else []


def _pedestrian_jaywalk(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    return s.modify(MotionIntent(cross_street=True, jaywalk=True)) if _kerb_side(s)[1] else []


#: The modify_pedestrian drafters, by intent kind, in the order they run for each named pedestrian.
PEDESTRIAN_DRAFTERS: tuple[tuple[str, Drafter], ...] = (
    ("pedestrian_speed_abs", _pedestrian_speed_abs), ("pedestrian_speed_rel", _pedestrian_speed_rel),
    ("pedestrian_run", _pedestrian_run), ("pedestrian_stop", _pedestrian_stop), ("pedestrian_delay", _pedestrian_delay),
    ("pedestrian_cross", _pedestrian_cross), ("pedestrian_jaywalk", _pedestrian_jaywalk),
)


def plan_modify_pedestrian(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    """Every :data:`PEDESTRIAN_DRAFTERS` draft about every named pedestrian."""
    return [d for agent, namer in _named(truth, rng, ("pedestrian",))
            for d in _drafts(_Subject(truth, agent, namer, {"T": namer()}), PEDESTRIAN_DRAFTERS, pools, rng)]


# ---------------------------------------------------------------------------------------------- remove
def plan_remove(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    del pools
    out = [Draft("remove_single" if agent.category in ("vehicle", "pedestrian") else "remove_static",
                 EditIntent("remove", (agent.object_id,)), {"T": phrase()})
           for agent, phrase in _named(truth, rng, ("vehicle", "pedestrian", "static", "sign"))]
    for phrase, ids in [*group_phrases(truth, rng), *static_groups(truth)]:
        out.append(Draft("remove_group", EditIntent("remove", ids, group=True), {"T": phrase}))
    return out


# ---------------------------------------------------------------------------------------------- infeasible
def _turn_without_intersection(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    """A turn for a vehicle driving away from the junction (refused: no intersection ahead)."""
    pos = s.truth.road_position(s.agent.traj["xy"][0], float(s.agent.traj["heading"][0]))
    if pos.arm is None or pos.inbound is not False or pos.along <= s.truth.layout.stopline_s(pos.arm):
        return []
    side = pick(rng, ("left", "right"))
    return [(EditIntent("modify", (s.oid,), motion=MotionIntent(turn=side), expected_refusals=("infeasible_motion",)),
             {"T": s.namer(), "side": side})]


def _pedestrian_lane_change(s: _Subject, pools: AssetPools, rng: np.random.Generator) -> Drafted:
    """A lane change for a pedestrian (refused: the wrong kind of agent)."""
    side = pick(rng, ("left", "right"))
    return [(EditIntent("modify", (s.oid,), motion=MotionIntent(lane_change=side),
                        expected_refusals=("wrong_category", "infeasible_motion")), {"T": s.namer(), "side": side})]


#: The infeasible drafters about named vehicles / pedestrians, by intent kind.
INFEASIBLE_VEHICLE_DRAFTERS: tuple[tuple[str, Drafter], ...] = (("turn_no_intersection", _turn_without_intersection),)
INFEASIBLE_PEDESTRIAN_DRAFTERS: tuple[tuple[str, Drafter], ...] = (
    ("pedestrian_lane_change", _pedestrian_lane_change),
)
#: Every drafter about a named agent, by intent kind: the ``prompt_forms`` kinds the behaviours declare
#: (``registry.PROMPT_FORMS``) and replacing a vehicle.
AGENT_DRAFTERS: dict[str, Drafter] = dict((*VEHICLE_DRAFTERS, *PEDESTRIAN_DRAFTERS, *INFEASIBLE_VEHICLE_DRAFTERS,
                                           *INFEASIBLE_PEDESTRIAN_DRAFTERS))


def plan_infeasible(truth: SceneTruth, pools: AssetPools, rng: np.random.Generator) -> list[Draft]:
    out: list[Draft] = []
    for _ in range(3):
        absent = absent_vehicle_phrase(truth, rng) if rng.random() < 0.7 else absent_pedestrian_phrase(rng)
        out.append(Draft("absent_remove", EditIntent("remove", expected_refusals=("not_found",), structured=False),
                         {"T": absent}))
        out.append(Draft("absent_modify", EditIntent("modify", expected_refusals=("not_found",), structured=False),
                         {"T": absent}))
        asset, words = _vehicle_asset(pools, rng)
        out.append(Draft("absent_anchor", EditIntent("insert", asset=asset, expected_refusals=("not_found",),
                                                     structured=False), {"A": words, "anchor": absent}))
        asset, words = _vehicle_asset(pools, rng)
        distance = float(pick(rng, ("10", "15", "20")))
        out.append(Draft("car_on_sidewalk", EditIntent(
            "insert", asset=asset, placement=PlacementIntent("on_sidewalk", EGO, distance),
            expected_refusals=("infeasible_placement",)), {"A": words, "d": distance_phrase(distance, rng)}))
    for category, drafters in (("vehicle", INFEASIBLE_VEHICLE_DRAFTERS),
                               ("pedestrian", INFEASIBLE_PEDESTRIAN_DRAFTERS)):
        out += [d for agent, namer in _named(truth, rng, (category,))
                for d in _drafts(_Subject(truth, agent, namer, {}), drafters, pools, rng)]
    for agent, phrase in _named(truth, rng, ("static", "sign")):
        words, value, mps = speed_words(8.0, "km/h", rng)
        out.append(Draft("static_motion", EditIntent(
            "modify", (agent.object_id,), motion=MotionIntent(speed_mps=mps, speed=SpeedWords("absolute", value,
                                                                                             "km/h")),
            expected_refusals=("wrong_category", "infeasible_motion")), {"T": phrase(), "v": words}))
    out += [Draft("nonsense", EditIntent("modify", expected_refusals=("unsupported",), structured=False))
            for _ in range(4)]
    return out


Planner = Callable[[SceneTruth, AssetPools, np.random.Generator], list[Draft]]
#: The planner of each prompt category (``prompts.CATEGORIES`` and ``"infeasible"``).
PLANNERS: dict[str, Planner] = {
    "add_vehicle": plan_add_vehicle,
    "add_static": plan_add_static,
    "add_pedestrian": plan_add_pedestrian,
    "modify_vehicle": plan_modify_vehicle,
    "modify_pedestrian": plan_modify_pedestrian,
    "remove": plan_remove,
    "infeasible": plan_infeasible,
}

__all__ = ["AGENT_DRAFTERS", "AssetPools", "Draft", "Drafter", "INFEASIBLE_PEDESTRIAN_DRAFTERS",
           "INFEASIBLE_VEHICLE_DRAFTERS", "PEDESTRIAN_DRAFTERS", "PLANNERS", "STATIC_ASSETS", "VEHICLE_DRAFTERS"]
