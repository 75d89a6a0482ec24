"""Grounded facts about one scene for proposing edits: who is where relative to the ego, what the road ahead
offers, which assets can be inserted.

    facts = scene_facts(ctx)                  # ctx: editing.draft.EditContext
    facts.agent("veh_02").caption             # "a white van"
    summary(facts).text()                     # the same facts as text lines (what an HTTP VLM reads)

Per object of the scene's language (``LanguageScene`` nodes, i.e. what grounding can find):

* what it is: category, caption ("a white SUV"), subtype, main colour;
* how it moves over the log: moving or standing, mean speed, and the motion class / location sector / map
  context that grounding reads (the language features' labels, ``scenario.vocabulary`` names);
* where it is at the reference frame (default the first; its first valid frame when absent then), in the ego
  frame (x ahead, y left): distance ahead and to the left, the sector it is in (45-degree sectors, as the
  labeller draws them), its heading relative to the ego's, and the area: the ego's lane, the lane left / right
  of it, an oncoming or another lane, the intersection, a crosswalk, a sidewalk, the road, off the road
  (``MapContext.facts`` and the lane graph);
* for vehicles, what the lane graph allows: a same-direction lane to change into on either side, the turns
  within reach before the log ends, and the free distance ahead and behind it in its direction.

The road (:class:`RoadFacts`) is read along the ego's lane path from the reference pose: how far the lane
goes on, where the first crosswalk and intersection start, the stretches of plain road (on the road, off
crosswalks and intersections) and how many lanes run each way. Assets (:class:`AssetFacts`) are the bank's.

Everything is plain Python values (frozen dataclasses of floats, strings, tuples), so facts compare, hash and
print; distances are metres, speeds m/s, angles degrees.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.language.motion_labels import LabelThresholds, location_sector
from simsplat_core.mining.scene_fact_records import ONCOMING_DEG, AgentFacts, AssetFacts, RoadFacts, SceneFacts
from simsplat_core.mining.vlm_protocol import SceneSummary
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph, LanePath
from simsplat_core.scenario.trajectory import agent_kind

if TYPE_CHECKING:
    from simsplat_core.editing.assets.bank import AssetBank
    from simsplat_core.editing.draft import EditContext
    from simsplat_core.language.scene_language import NodeLanguage

logger = logging.getLogger(__name__)

#: Words of each area in the summary.
AREA_WORDS: dict[str, str] = {
    "ego_lane": "in the ego lane",
    "left_lane": "in the lane left of the ego's",
    "right_lane": "in the lane right of the ego's",
    "oncoming_lane": "in an oncoming lane",
    "other_lane": "in another lane",
    "intersection": "in the intersection",
    "crosswalk": "on a crosswalk",
    "sidewalk": "on a sidewalk",
    "road": "on the road",
    "off_road": "off the road",
}
#: Mean speed (m/s) above which an agent counts as moving.
MOVING_MPS = 0.5
#: How far along the ego's lanes the road is read (m), and the sampling step.
ROAD_LOOKAHEAD_M = 120.0
ROAD_STEP_M = 1.0
#: A lane within this of a point (m) is the point's lane.
LANE_REACH_M = 2.5
#: Half width of the corridor in which another agent blocks a vehicle's way (m).
CORRIDOR_HALF_WIDTH_M = 2.5


# ---------------------------------------------------------------------------------------------- geometry
def _to_ego(xy: np.ndarray, ego_xy: np.ndarray, ego_heading: float) -> np.ndarray:
    """``[N, 2]`` world points in the ego frame (x ahead, y left)."""
    c, s = math.cos(ego_heading), math.sin(ego_heading)
    d = np.asarray(xy, dtype=np.float64).reshape(-1, 2) - ego_xy
    return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)


def _reference_step(states: AgentStates, row: int, frame: int) -> int | None:
    """``frame`` when the agent is there, else its first valid step (``None``: never valid)."""
    valid = states.valid[row]
    if 0 <= frame < len(valid) and valid[frame]:
        return frame
    steps = np.flatnonzero(valid)
    return int(steps[0]) if steps.size else None


def _ego_path(lanes: LaneGraph, xy: np.ndarray, heading: float) -> LanePath | None:
    try:
        return lanes.follow(xy, heading, "straight", max_length_m=ROAD_LOOKAHEAD_M)
    except ValueError:  # no lane near the ego
        return None


def _stretches(mask: np.ndarray, s: np.ndarray) -> tuple[tuple[float, float], ...]:
    """``(start, end)`` arc lengths of the runs of ``True`` in ``mask`` over samples ``s``."""
    out = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    for a, b in zip(edges[::2], edges[1::2]):
        out.append((round(float(s[a]), 1), round(float(s[b - 1]), 1)))
    return tuple(out)


def _first(mask: np.ndarray, s: np.ndarray) -> float | None:
    hits = np.flatnonzero(mask)
    return round(float(s[hits[0]]), 1) if hits.size else None


def _lanes_beside(lanes: LaneGraph, xy: np.ndarray, heading: float, reach_m: float = 15.0) -> tuple[int, int]:
    """Distinct lanes crossed by the ego's perpendicular within ``reach_m``: ``(our way, oncoming)``."""
    normal = np.array([-math.sin(heading), math.cos(heading)])
    probes = xy + np.arange(-reach_m, reach_m + 0.5, 0.5)[:, None] * normal  # [P, 2]
    counts = []
    for way in (heading, heading + math.pi):
        match = lanes.nearest(probes, np.full(len(probes), way), align_deg=30.0, max_dist_m=1.0)
        counts.append(len(set(int(k) for k in match.lane if k >= 0)))
    return counts[0], counts[1]


def _road_facts(ctx: EditContext, states: AgentStates, ego_xy: np.ndarray, ego_heading: float) -> tuple[
        RoadFacts, LanePath | None]:
    ego = states.index(EGO_ID)
    ego_speed = float(np.abs(states.speed[ego][states.valid[ego]]).mean()) if states.valid[ego].any() else 0.0
    duration = float(states.times[-1] - states.times[0]) if states.num_steps else 0.0
    sidewalks = ctx.map_ctx.has_sidewalks
    path = _ego_path(ctx.lanes, ego_xy, ego_heading)
    if path is None:
        return RoadFacts(ego_speed_mps=ego_speed, sidewalks=sidewalks, duration_s=duration), None
    ahead = min(path.path.length - path.start_s, ROAD_LOOKAHEAD_M)
    s = np.arange(0.0, ahead + 1e-9, ROAD_STEP_M)  # [K] metres ahead
    points, headings = path.path.position(path.start_s + s), path.path.heading(path.start_s + s)
    facts = ctx.map_ctx.facts(points, headings)
    on_road = facts.on_drivable if ctx.map_ctx.has_drivable else np.isfinite(facts.lane_dist)
    plain = on_road & ~facts.in_crosswalk & ~facts.at_intersection
    lane = path.lanes[0]
    our_way, oncoming = _lanes_beside(ctx.lanes, ego_xy, ego_heading)
    road = RoadFacts(
        ego_speed_mps=round(ego_speed, 2), lane_ahead_m=round(float(ahead), 1),
        crosswalk_ahead_m=_first(facts.in_crosswalk, s), intersection_ahead_m=_first(facts.at_intersection, s),
        plain_road=_stretches(plain, s), left_lane=bool(ctx.lanes.left[lane] >= 0),
        right_lane=bool(ctx.lanes.right[lane] >= 0), lanes_our_way=max(our_way, 1), lanes_oncoming=oncoming,
        sidewalks=sidewalks, duration_s=round(duration, 2))
    return road, path


# ---------------------------------------------------------------------------------------------- agents
def _labels(node: NodeLanguage) -> tuple[str, str, str]:
    """Grounded ``(motion, sector, context)`` of a node ("" where the scene has none)."""
    if node.motion is not None:
        probs = node.motion.location_probs
        sector = max(voc.LOCATION_SECTOR.names, key=lambda n: probs.get(n, 0.0))
        context = max(voc.LOCATION_CONTEXT.names, key=lambda n: probs.get(n, 0.0))
        return node.motion.motion, sector, context
    if node.static_location:
        return "", max(node.static_location, key=node.static_location.__getitem__), ""
    return "", "", ""


def _area(kind: str, xy: np.ndarray, heading: float, rel_heading_deg: float, ctx: EditContext,
          lane_sets: tuple[set[int], set[int], set[int]]) -> str:
    """One of :data:`AREAS` for a point ``[2]`` with ``heading`` (radians, world)."""
    facts = ctx.map_ctx.facts(xy[None], np.array([heading]))
    ego_lanes, left_lanes, right_lanes = lane_sets
    if kind != "vehicle":
        if facts.in_crosswalk[0]:
            return "crosswalk"
        if facts.on_sidewalk[0]:
            return "sidewalk"
    match = ctx.lanes.nearest(xy[None], np.array([heading]) if kind == "vehicle" else None,
                              max_dist_m=LANE_REACH_M if kind == "vehicle" else 1.8)
    lane = int(match.lane[0])
    for name, members in (("ego_lane", ego_lanes), ("left_lane", left_lanes), ("right_lane", right_lanes)):
        if lane >= 0 and lane in members and (kind != "vehicle" or abs(rel_heading_deg) < 90.0):
            return name
    if kind == "vehicle" and abs(rel_heading_deg) >= ONCOMING_DEG and (lane >= 0 or facts.on_drivable[0]):
        return "oncoming_lane"
    if facts.at_intersection[0]:
        return "intersection"
    if kind == "vehicle" and lane >= 0:
        return "other_lane"
    if facts.on_drivable[0] or (not ctx.map_ctx.has_drivable and np.isfinite(facts.lane_dist[0])):
        return "road"
    return "sidewalk" if facts.on_sidewalk[0] else "off_road"


def _lane_change_sides(lanes: LaneGraph, xy: np.ndarray, heading: float) -> tuple[str, ...]:
    match = lanes.nearest(xy[None], np.array([heading]), max_dist_m=LANE_REACH_M)
    lane = int(match.lane[0])
    if lane < 0:
        return ()
    return tuple(side for side, table in (("left", lanes.left), ("right", lanes.right)) if table[lane] >= 0)


def _turns(lanes: LaneGraph, xy: np.ndarray, heading: float, reach_m: float) -> tuple[str, ...]:
    """Turns whose turning lane the agent gets halfway through within ``reach_m`` of travel."""
    out = []
    for turn in ("left", "right"):
        try:
            path = lanes.follow(xy, heading, turn, max_length_m=reach_m + 60.0)
        except ValueError:
            return ()
        if not path.turn_taken:
            continue
        for k, lane in enumerate(path.lanes):
            if lanes.turn_of(lane) == turn:
                start, end = path.lane_span(k)
                if 0.5 * (start + end) - path.start_s <= reach_m:
                    out.append(turn)
                break
    return tuple(out)


def _room(states: AgentStates, row: int, step: int) -> tuple[float, float]:
    """Free distance ahead of and behind agent ``row`` along its heading at ``step`` to any other agent at any
    step inside the corridor (bumper to bumper; ``inf`` when clear)."""
    heading = float(states.heading[row, step])
    others = [r for r in range(states.num_agents) if r != row]
    if not others:
        return math.inf, math.inf
    rel = _to_ego(states.xy[others].reshape(-1, 2), states.xy[row, step], heading).reshape(len(others), -1, 2)
    valid = states.valid[others]  # [O, T]
    inside = valid & (np.abs(rel[..., 1]) < CORRIDOR_HALF_WIDTH_M)
    half = 0.5 * states.size[row, 0] + 0.5 * states.size[others, 0][:, None]  # [O, 1]
    gap_ahead = np.where(inside & (rel[..., 0] > 0), rel[..., 0] - half, np.inf)
    gap_behind = np.where(inside & (rel[..., 0] < 0), -rel[..., 0] - half, np.inf)
    return round(max(float(gap_ahead.min()), 0.0), 1), round(max(float(gap_behind.min()), 0.0), 1)


def _agent_facts(ctx: EditContext, node: NodeLanguage, frame: int, ego_xy: np.ndarray, ego_heading: float,
                 lane_sets: tuple[set[int], set[int], set[int]], visible: dict[str, float]) -> AgentFacts | None:
    states = ctx.states
    try:
        row = states.index(node.object_id)
    except KeyError:
        return None
    step = _reference_step(states, row, frame)
    if step is None:
        return None
    category = states.categories[row]
    kind = agent_kind(category) or "static"
    xy, heading = states.xy[row, step], float(states.heading[row, step])
    rel = _to_ego(xy, ego_xy, ego_heading)[0]
    rel_heading = float(np.rad2deg(wrap_angle(heading - ego_heading)))
    rel_heading = 180.0 if rel_heading <= -180.0 else rel_heading
    valid = states.valid[row]
    speed = float(np.abs(states.speed[row][valid]).mean()) if kind != "static" else 0.0
    moving = speed > MOVING_MPS
    motion, sector, context = _labels(node)
    caption = node.caption
    sides: tuple[str, ...] = ()
    turns: tuple[str, ...] = ()
    room = (math.inf, math.inf)
    if kind == "vehicle":
        sides = _lane_change_sides(ctx.lanes, xy, heading)
        remaining = float(states.times[valid][-1] - states.times[step])
        turns = _turns(ctx.lanes, xy, heading, speed * remaining) if moving else ()
        room = _room(states, row, step)
    return AgentFacts(
        object_id=node.object_id, node_id=node.node_id, category=category, kind=kind,
        caption=caption.text if caption is not None else "", subtype=caption.subtype if caption is not None else "",
        color=caption.color if caption is not None and caption.colors else "", motion=motion, sector=sector,
        context=context, moving=moving, speed_mps=round(speed, 2), ahead_m=round(float(rel[0]), 1),
        left_m=round(float(rel[1]), 1), heading_deg=round(rel_heading, 1),
        relation=location_sector(rel, LabelThresholds()),
        area=_area(kind, xy, heading, rel_heading, ctx, lane_sets), lane_change_sides=sides, turns=turns,
        room_ahead_m=room[0], room_behind_m=room[1], visible_share=round(visible.get(node.object_id, 0.0), 2),
        frame=int(states.frame_idx[step]))


def _asset_facts(bank: AssetBank | None) -> tuple[AssetFacts, ...]:
    if bank is None:
        return ()
    return tuple(AssetFacts(a.category, a.subtype, a.color, a.caption) for a in bank.assets)


def scene_facts(ctx: EditContext, frame: int = 0) -> SceneFacts:
    """The facts of ``ctx``'s scene at step ``frame`` (module docstring)."""
    states = ctx.states
    ego = states.index(EGO_ID)
    step = _reference_step(states, ego, frame)
    if step is None:
        raise ValueError(f"{ctx.log.seq_id}: the ego has no valid step")
    ego_xy, ego_heading = states.xy[ego, step].copy(), float(states.heading[ego, step])
    road, path = _road_facts(ctx, states, ego_xy, ego_heading)
    ego_lanes = set(path.lanes) if path is not None else set()
    left = {int(ctx.lanes.left[k]) for k in ego_lanes if ctx.lanes.left[k] >= 0}
    right = {int(ctx.lanes.right[k]) for k in ego_lanes if ctx.lanes.right[k] >= 0}
    visible = {t.object_id: float(np.mean(t.visible)) for t in ctx.log.tracks if len(t) > 0}
    agents = []
    for node in ctx.language.nodes:
        found = _agent_facts(ctx, node, step, ego_xy, ego_heading, (ego_lanes, left, right), visible)
        if found is not None:
            agents.append(found)
    facts = SceneFacts(ctx.log.seq_id, tuple(agents), road, _asset_facts(ctx.bank))
    logger.debug("%s: facts of %d agents, %d assets", facts.seq_id, len(facts.agents), len(facts.assets))
    return facts


# ---------------------------------------------------------------------------------------------- as text
def _where(a: AgentFacts) -> str:
    along = f"{abs(a.ahead_m):.0f} m {'ahead' if a.ahead_m >= 0 else 'behind'}"
    side = f"{abs(a.left_m):.0f} m to the {'left' if a.left_m >= 0 else 'right'}" if abs(a.left_m) >= 1.0 else ""
    return " and ".join(p for p in (along, side) if p)


def agent_line(a: AgentFacts) -> str:
    """``"veh_02: a white van, 33 m ahead and 11 m to the left, in an oncoming lane, moving at 6.2 m/s
    (stopping)"``."""
    what = a.caption or f"a {a.category}"
    state = f"moving at {a.speed_mps:.1f} m/s" if a.moving else (voc.STANDING if a.kind != "static" else "static")
    motion = f" ({a.motion.replace('_', ' ')})" if a.motion else ""
    extra = []
    if a.lane_change_sides:
        extra.append(f"may change lanes to the {' or '.join(a.lane_change_sides)}")
    if a.turns:
        extra.append(f"may turn {' or '.join(a.turns)} ahead")
    tail = f"; {', '.join(extra)}" if extra else ""
    return f"{a.object_id}: {what}, {_where(a)}, {AREA_WORDS[a.area]}, {state}{motion}{tail}"


def road_lines(road: RoadFacts) -> list[str]:
    """The ego and the road ahead as text lines."""
    lanes = f"{road.lanes_our_way} lane(s) our way, {road.lanes_oncoming} oncoming"
    sides = [side for side, has in (("left", road.left_lane), ("right", road.right_lane)) if has]
    if sides:
        lanes += f"; a lane to the ego's {' and '.join(sides)}"
    ahead = [f"the ego lane goes on {road.lane_ahead_m:.0f} m"]
    if road.intersection_ahead_m is not None:
        ahead.append(f"intersection {road.intersection_ahead_m:.0f} m ahead")
    if road.crosswalk_ahead_m is not None:
        ahead.append(f"crosswalk {road.crosswalk_ahead_m:.0f} m ahead")
    plain = ", ".join(f"{a:.0f}-{b:.0f} m" for a, b in road.plain_road) or "none"
    return [f"ego: driving at {road.ego_speed_mps:.1f} m/s; the log lasts {road.duration_s:.1f} s",
            f"map: {'; '.join(ahead)}; {lanes}; sidewalks: {'yes' if road.sidewalks else 'no'}",
            f"map: plain road ahead of the ego (off crosswalks and intersections): {plain}"]


def summary(facts: SceneFacts) -> SceneSummary:
    """``facts`` as a :class:`SceneSummary`: text lines (ego and road, one per agent, the assets) and the facts."""
    lines = road_lines(facts.road) + [agent_line(a) for a in facts.agents]
    if facts.assets:
        kinds = sorted({f"{a.category}: {a.caption}" for a in facts.assets})
        lines.append("assets that can be inserted: " + "; ".join(kinds))
    else:
        lines.append("assets that can be inserted: none (no asset bank)")
    return SceneSummary(facts.seq_id, tuple(lines), facts=facts)


__all__ = ["agent_line", "road_lines", "scene_facts", "summary"]
