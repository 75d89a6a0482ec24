"""Where an inserted (or moved) object goes: ``commands.Placement`` resolved against the anchor, the lane graph
and the map.

``resolve_placement`` turns a relation into a world pose:

* ``left_of`` / ``right_of`` / ``in_front_of`` / ``behind`` / ``next_to`` -- beside the anchor in its own frame,
  ``distance_m`` between the box edges (default :data:`SIDE_GAP_M` sideways, :data:`LONG_GAP_M` lengthwise);
  ``next_to`` tries the right side, then the left;
* ``in_lane`` -- in the anchor's lane (``same``), its ``left`` / ``right`` neighbour or the ``opposite`` lane,
  ``distance_m`` ahead of the anchor's projection along the lane graph (centre to centre; default
  :data:`LANE_AHEAD_M`), oriented along the lane;
* ``on_crosswalk`` / ``on_sidewalk`` / ``on_road`` -- the nearest spot of that kind of map area where the box
  fits, from the anchor; with ``distance_m``, about that far ahead of it (within :func:`distance_slack`), on the
  side of the road edge nearest the anchor when both sides have one; a pedestrian or static object stays inside
  that area when nudged;
* ``absolute`` -- ``position`` in the ego frame at ``frame`` (the ego frame's origin is on the ground).

Rules per kind (``scenario.metrics.kind_of``): a vehicle ends up on a lane centre line, oriented along the
lane (snapped from within :data:`LANE_SNAP_M`), and still on the requested side of its anchor -- except
behind / in front of a vehicle parked on the road outside the lanes (a parking strip, a shoulder): there it
parks in line with it, on the anchor's heading line, its whole box on the drivable area and off the sidewalks
(area ``"road"``, no lane); a pedestrian may stand on sidewalks, crosswalks or the road, a static object on the
road or a sidewalk (anywhere, on a map without sidewalks). A pedestrian about to cross the road
(``crossing=True``) placed behind / in front of its anchor stands at the edge of the road beside that spot
(within :data:`KERB_REACH_M`), facing across it. A box overlapping an agent at that frame is nudged along its
lane (or heading) by up to :data:`NUDGE_M` (:data:`QUEUE_REACH_M` behind / in front of an anchor with no
distance said; :func:`distance_slack` of a given distance, when more; away from the anchor first when no
distance is given); otherwise the placement is refused, naming the object in the way.
Refusals are ``EditRefused(reason="infeasible_placement")`` ("cannot place a car on the sidewalk", "no lane to
the left of the white van").
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.commands import Placement
from simsplat_core.editing.motion.routes import crosswalk_ends, nearest_lane_segment
from simsplat_core.editing.placement.areas import (
    AREA_SEARCH_M,
    area_polygons,
    box_points,
    box_within,
    fitting_point,
    fitting_point_ahead,
    in_any,
    lane_samples,
    longest_run_heading,
    road_edge_offset,
)
from simsplat_core.editing.result import EditRefused
from simsplat_core.geometry import yaw_of_rotation
from simsplat_core.scenario.agents import EGO_ID, EGO_SIZE, AgentStates
from simsplat_core.scenario.geometry import box_footprints, footprints_overlap
from simsplat_core.scenario.lane_graph import LaneGraph, LaneMatch
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import STATIC, kind_of
from simsplat_core.scenario.path import Path
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE

logger = logging.getLogger(__name__)

#: Default gap between box edges beside (``left_of`` / ``right_of`` / ``next_to``) and before / behind, m.
SIDE_GAP_M = 1.0
LONG_GAP_M = 3.0
#: Default centre-to-centre distance ahead of the anchor of ``in_lane`` placements, m.
LANE_AHEAD_M = 10.0
#: A vehicle is snapped onto a lane centre line within this distance, m.
LANE_SNAP_M = 2.5
#: An anchor slower than this counts as standing (parked, when off the lanes), m/s.
STANDING_MPS = 0.5
#: Boxes are nudged by up to this much (in ``NUDGE_STEP_M`` steps) to clear another agent; clearance kept, m.
NUDGE_M = 4.0
NUDGE_STEP_M = 0.5
#: ... or this much behind / in front of an anchor with no distance said: "behind the pickup" where a car
#: already waits right behind it is behind that car.
QUEUE_REACH_M = 10.0
CLEARANCE_M = 0.3
#: A said distance may be met this loosely (share of it, at least ``NUDGE_M``) when the exact spot is taken or
#: is not of the asked kind of area.
DISTANCE_SLACK_SHARE = 0.25
#: The road edge a crossing pedestrian starts at is looked for this far to either side, m; it stands this far
#: inside it (besides half its width), m.
KERB_REACH_M = 10.0
KERB_INSET_M = 0.2
#: The side of the road nearest the anchor (for ``on_sidewalk`` etc. ``distance_m`` ahead) is looked for this
#: far to either side of it, m.
EDGE_SIDE_REACH_M = 30.0
#: Words for messages.
_NOUNS = {VEHICLE: "a car", PEDESTRIAN: "a pedestrian", STATIC: "a static object"}
_AREA_KIND = {"on_crosswalk": "crosswalk", "on_sidewalk": "sidewalk", "on_road": "road"}


@dataclass(frozen=True)
class AnchorPose:
    """The object a placement is relative to, at the placement's frame.

    Attributes:
        xy: ``[2]`` world box centre, m; heading: yaw, rad; size: ``(length, width, height)``, m.
        category: its category; object_id: its id (``"ego"`` for the ego).
        z: box-centre height, m (the placed object stands on the same ground).
        label: how messages name it ("the white van"); default ``"<category> '<object_id>'"``.
        speed: its speed then, m/s (a parked anchor stands still).
    """

    xy: np.ndarray
    heading: float
    size: tuple[float, float, float]
    category: str
    object_id: str
    z: float = 0.0
    label: str = ""
    speed: float = 0.0

    @property
    def name(self) -> str:
        if self.label:
            return self.label
        return "the ego vehicle" if self.object_id == EGO_ID else f"{self.category} {self.object_id!r}"

    @property
    def forward(self) -> np.ndarray:
        return np.array([np.cos(self.heading), np.sin(self.heading)])

    @property
    def left(self) -> np.ndarray:
        return np.array([-np.sin(self.heading), np.cos(self.heading)])

    @classmethod
    def ego(cls, ego_pose: np.ndarray) -> AnchorPose:
        """The ego at ``ego_pose [4, 4]`` (ego origin on the ground)."""
        return cls(np.asarray(ego_pose[:2, 3], dtype=np.float64), float(yaw_of_rotation(ego_pose[:3, :3])),
                   EGO_SIZE, "vehicle", EGO_ID, float(ego_pose[2, 3]) + EGO_SIZE[2] / 2.0)

    @classmethod
    def from_states(cls, states: AgentStates, row: int, step: int, label: str = "") -> AnchorPose:
        """Agent ``row`` at step ``step`` (raises ``ValueError`` when it does not exist there)."""
        if not states.valid[row, step]:
            raise ValueError(f"agent {states.object_ids[row]!r} does not exist at step {step}")
        return cls(states.xy[row, step].copy(), float(states.heading[row, step]),
                   tuple(float(x) for x in states.size[row]),  # type: ignore[arg-type]
                   states.categories[row], states.object_ids[row], float(states.z[row, step]), label,
                   float(states.speed[row, step]))


@dataclass(frozen=True)
class PlacedPose:
    """A resolved placement.

    Attributes:
        xy: ``[2]`` world box centre, m; heading: yaw, rad.
        lane: the lane it was placed on (one-row ``LaneMatch``), ``None`` off lanes.
        z: box-centre height, m (the anchor's ground, or the absolute point's height, plus half the box).
        area: what it stands on: ``"lane"``, ``"road"``, ``"crosswalk"``, ``"sidewalk"`` or ``"unknown"``.
        note: adjustments made (``"nudged 1.5 m ahead to clear vehicle 'car_3'"``), ``""`` when none.
        parked: a vehicle parked outside the lanes (in line with a parked anchor; ``lane`` is ``None``).
    """

    xy: np.ndarray
    heading: float
    lane: LaneMatch | None
    z: float = 0.0
    area: str = "unknown"
    note: str = ""
    parked: bool = False


def distance_slack(distance_m: float) -> float:
    """How far (m) a placement asked ``distance_m`` away may end up from that distance: a share of it, at least
    :data:`NUDGE_M`."""
    return max(NUDGE_M, DISTANCE_SLACK_SHARE * abs(distance_m))


def resolve_placement(placement: Placement, *, category: str, size: Sequence[float], anchor: AnchorPose | None,  # noqa: PLR0913 -- keyword-only: the scene context a placement is resolved in
                      ego_pose: np.ndarray, lanes: LaneGraph | None, map_ctx: MapContext, frame: int,
                      occupied: AgentStates | None, ignore: Sequence[str] = (), crossing: bool = False) -> PlacedPose:
    """Resolve ``placement`` for an object of ``category`` and box ``size (l, w, h)`` (module docstring).

    Args:
        anchor: the grounded anchor at ``frame``; ``None`` = the ego at ``ego_pose``.
        ego_pose: ``[4, 4]`` ego pose at ``frame`` (ego frame -> world).
        lanes: the lane graph (required for vehicles and ``in_lane``).
        occupied: every agent; the box must not overlap one valid at ``frame`` (``None``: no check).
        ignore: object ids not to check against (the agent being moved).
        crossing: the (pedestrian) object will cross the road from there: behind / in front of the anchor it
            starts at the road's edge.

    Raises:
        EditRefused(reason="infeasible_placement"): see the module docstring.
    """
    kind = kind_of(category)
    size3 = (float(size[0]), float(size[1]), float(size[2]))
    anchor = anchor if anchor is not None else AnchorPose.ego(np.asarray(ego_pose, dtype=np.float64))
    ego_yaw = float(yaw_of_rotation(np.asarray(ego_pose)[:3, :3]))
    hint = None if placement.heading_deg is None else ego_yaw + np.deg2rad(placement.heading_deg)
    ctx = _Context(placement, kind, size3, anchor, lanes, map_ctx, hint, _parked_off_lane(anchor, lanes, map_ctx))
    rel = placement.relation
    if rel == "absolute":
        assert placement.position is not None
        point = np.asarray(ego_pose, dtype=np.float64) @ np.r_[np.asarray(placement.position, np.float64), 1.0]
        spots = [_Spot(point[:2], ego_yaw if hint is None else hint, "at the given position", None)]
        z = float(point[2]) + size3[2] / 2.0
    else:
        z = anchor.z - anchor.size[2] / 2.0 + size3[2] / 2.0
        if rel == "in_lane":
            spots = [_lane_spot(ctx)]
        elif rel in _AREA_KIND:
            spots = [_area_spot(ctx, _AREA_KIND[rel])]
        else:
            sides = ("right_of", "left_of") if rel == "next_to" else (rel,)
            spots = [_beside_spot(ctx, side) for side in sides]
            if crossing and kind == PEDESTRIAN and rel in ("behind", "in_front_of"):
                spots = [_kerb_spot(ctx, spot) for spot in spots]
    refusals: list[str] = []
    for spot in spots:
        try:
            placed = _settle(ctx, spot)
            return _clear(ctx, placed, spot, occupied, frame, ignore, z)
        except EditRefused as err:
            refusals.append(str(err))
    raise EditRefused(" / ".join(dict.fromkeys(refusals)), reason="infeasible_placement")


# ---------------------------------------------------------------------------------------------- internals
@dataclass(frozen=True)
class _Context:
    placement: Placement
    kind: str
    size: tuple[float, float, float]
    anchor: AnchorPose
    lanes: LaneGraph | None
    map_ctx: MapContext
    hint: float | None
    parked_anchor: bool = False

    @property
    def noun(self) -> str:
        return _NOUNS[self.kind]


def _parked_off_lane(anchor: AnchorPose, lanes: LaneGraph | None, map_ctx: MapContext) -> bool:
    """Whether ``anchor`` is a vehicle standing (below :data:`STANDING_MPS`) on the drivable area but off every
    lane (farther than :data:`LANE_SNAP_M` from any centre line, off the sidewalks): parked at the roadside."""
    if (kind_of(anchor.category) != VEHICLE or abs(anchor.speed) >= STANDING_MPS or lanes is None or not len(lanes)
            or not map_ctx.has_drivable):
        return False
    if lanes.nearest(anchor.xy[None], max_dist_m=LANE_SNAP_M).lane[0] >= 0:
        return False
    facts = map_ctx.facts(anchor.xy[None], np.array([anchor.heading]))
    return bool(facts.on_drivable[0] and not facts.on_sidewalk[0])


@dataclass(frozen=True)
class _Spot:
    """A candidate before the category rules: ``xy [2]``, heading, how it was asked (for messages), the
    relation side it must stay on (``"left_of"`` ...; ``None``: no side) and the kind of map area a pedestrian or
    static object must stay inside (``"sidewalk"`` ...; ``None``: any)."""

    xy: np.ndarray
    heading: float
    phrase: str
    side: str | None
    area: str | None = None


def _refuse(message: str) -> EditRefused:
    return EditRefused(message, reason="infeasible_placement")


def _beside_spot(ctx: _Context, side: str) -> _Spot:
    a, (length, width, _) = ctx.anchor, ctx.size
    al, aw = a.size[0], a.size[1]
    lateral = side in ("left_of", "right_of")
    gap = ctx.placement.distance_m if ctx.placement.distance_m is not None else (SIDE_GAP_M if lateral else LONG_GAP_M)
    sign = 1.0 if side in ("left_of", "in_front_of") else -1.0
    heading = a.heading if ctx.hint is None else ctx.hint
    if lateral:
        xy = a.xy + sign * (aw / 2.0 + gap + width / 2.0) * a.left
    else:
        xy = a.xy + sign * (al / 2.0 + gap + length / 2.0) * a.forward
    words = {"left_of": "to the left of", "right_of": "to the right of", "in_front_of": "in front of",
             "behind": "behind"}[side]
    return _Spot(xy, float(heading), f"{words} {a.name}", side)


def _anchor_lane(ctx: _Context) -> int:
    lanes, a = ctx.lanes, ctx.anchor
    if lanes is None or not len(lanes):
        raise _refuse(f"cannot place {ctx.noun} in a lane: this map has no lanes")
    m = lanes.nearest(a.xy[None], np.array([a.heading]), align_deg=45.0, max_dist_m=4.0)
    if m.lane[0] < 0:
        m = lanes.nearest(a.xy[None], max_dist_m=6.0)
    if m.lane[0] < 0:
        raise _refuse(f"cannot place {ctx.noun} in {a.name}'s lane: {a.name} is not on a lane")
    return int(m.lane[0])


def _lane_spot(ctx: _Context) -> _Spot:
    lanes, a, p = ctx.lanes, ctx.anchor, ctx.placement
    lane = _anchor_lane(ctx)
    assert lanes is not None
    choice = p.lane or "same"
    if choice in ("left", "right"):
        lane = int((lanes.left if choice == "left" else lanes.right)[lane])
        if lane < 0:
            raise _refuse(f"no lane to the {choice} of {a.name}")
    elif choice == "opposite":
        lane = _opposite_lane(ctx)
    default = max(LANE_AHEAD_M, (a.size[0] + ctx.size[0]) / 2.0 + LONG_GAP_M)
    dist = p.distance_m if p.distance_m is not None else default
    ln = lanes.lanes[lane]
    centre = Path.from_points(ln.points)
    s_on = centre.project(a.xy)
    if choice == "opposite":  # its lane runs towards the anchor: "ahead of the anchor" is back along it
        xy = centre.position(s_on - dist)
        heading = float(ln.heading_at(max(s_on - dist, 0.0)))
    else:
        lp = lanes.follow(centre.position(s_on), float(ln.heading_at(s_on)), "straight", max_length_m=dist + 50.0)
        xy, heading = lp.path.position(lp.start_s + dist), float(lp.path.heading(lp.start_s + dist))
    words = {"same": f"in {a.name}'s lane", "left": f"in the lane left of {a.name}",
             "right": f"in the lane right of {a.name}", "opposite": f"in the oncoming lane next to {a.name}"}
    return _Spot(np.asarray(xy, np.float64), heading, f"{words[choice]} {dist:.0f} m ahead", None)


def _opposite_lane(ctx: _Context) -> int:
    """The nearest lane running against the anchor within 12 m, preferably on its left."""
    lanes, a = ctx.lanes, ctx.anchor
    assert lanes is not None
    m = lanes.nearest(a.xy[None], np.array([a.heading + np.pi]), align_deg=45.0, max_dist_m=12.0)
    if m.lane[0] < 0:
        raise _refuse(f"no oncoming lane next to {a.name}")
    return int(m.lane[0])


def _area_spot(ctx: _Context, area: str) -> _Spot:
    a, p, mc = ctx.anchor, ctx.placement, ctx.map_ctx
    if area == "sidewalk" and ctx.kind == VEHICLE:
        raise _refuse(f"cannot place {ctx.noun} on the sidewalk: vehicles go in lanes (try 'in the lane' or "
                      "'on the road')")
    polys = area_polygons(mc, area)
    if not polys:
        raise _refuse(f"cannot place {ctx.noun} on a {area}: this map has no {area}s")
    query = a.xy + (p.distance_m or 0.0) * a.forward
    heading = a.heading if ctx.hint is None else ctx.hint
    if ctx.kind == VEHICLE and ctx.lanes is not None and len(ctx.lanes):
        # a car on the road / a crosswalk: the nearest lane point inside such an area
        pts, yaw = lane_samples(ctx.lanes)
        inside = np.flatnonzero(in_any(pts, polys))
        if inside.size:
            turned = np.abs(np.angle(np.exp(1j * (yaw[inside] - heading)))) > np.pi / 4
            score = np.linalg.norm(pts[inside] - query, axis=1) + 50.0 * turned  # lanes running the anchor's way
            xy = pts[inside[int(np.argmin(score))]]
            return _Spot(xy, float(heading), f"on the {area} nearest {a.name}", None)
    if p.distance_m is None:
        xy = fitting_point(query, polys, ctx.size)
        where = f"within {AREA_SEARCH_M:.0f} m of {a.name}"
    else:
        slack = distance_slack(p.distance_m)
        xy = fitting_point_ahead(a.xy, a.heading, p.distance_m, slack, polys, ctx.size, _edge_side(ctx))
        where = f"{p.distance_m:g} m (+-{slack:.0f} m) ahead of {a.name}"
    if xy is None:
        raise _refuse(f"cannot place {ctx.noun} on a {area}: none {where} fits it")
    if ctx.hint is None:
        heading = _area_heading(ctx, area, xy, polys, heading)
    return _Spot(xy, float(heading), f"on the {area} nearest {a.name}", None, area)


def _edge_side(ctx: _Context) -> int:
    """Side (``+1`` left, ``-1`` right, ``0`` unknown) of the road edge nearest the anchor."""
    offset = road_edge_offset(ctx.map_ctx, ctx.anchor.xy, ctx.anchor.left, EDGE_SIDE_REACH_M)
    return 0 if offset is None else int(np.sign(offset))


def _kerb_spot(ctx: _Context, spot: _Spot) -> _Spot:
    """``spot`` moved sideways to just inside the nearer road edge (within :data:`KERB_REACH_M`), facing across
    the road (``spot`` itself off the road, or with no edge in reach)."""
    left = ctx.anchor.left
    offset = road_edge_offset(ctx.map_ctx, spot.xy, left, KERB_REACH_M)
    inset = ctx.size[1] / 2.0 + KERB_INSET_M
    if offset is None or abs(offset) <= inset:
        return spot
    sign = float(np.sign(offset))
    xy = spot.xy + (offset - sign * inset) * left
    across = -sign * left
    heading = float(np.arctan2(across[1], across[0])) if ctx.hint is None else spot.heading
    return _Spot(xy, heading, f"{spot.phrase} at the road's edge", spot.side)


def _area_heading(ctx: _Context, area: str, xy: np.ndarray, polys: Sequence[np.ndarray], heading: float) -> float:
    """Along the crosswalk's long axis (away from the anchor's side), along the sidewalk where it runs on the
    longest (the way nearest ``heading`` on a tie), else along the nearest lane segment (the way agreeing with
    ``heading``)."""
    if area == "crosswalk":
        poly = next(p for p in polys if in_any(xy[None], [p])[0])
        end_a, end_b = crosswalk_ends(poly)
        axis = (end_b - end_a) / np.linalg.norm(end_b - end_a)
        if np.dot(axis, poly.mean(axis=0) - ctx.anchor.xy) < 0:
            axis = -axis
        return float(np.arctan2(axis[1], axis[0]))
    if area == "sidewalk":
        return longest_run_heading(xy, polys, heading)
    nearest = nearest_lane_segment(ctx.map_ctx, xy)
    if nearest is None:
        return heading
    d = nearest[1] if np.dot(nearest[1], [np.cos(heading), np.sin(heading)]) >= 0 else -nearest[1]
    return float(np.arctan2(d[1], d[0]))


def _where(ctx: _Context, xy: np.ndarray, heading: float) -> str:
    facts = ctx.map_ctx.facts(xy[None], np.array([heading]))
    if facts.in_crosswalk[0]:
        return "crosswalk"
    if facts.on_sidewalk[0]:
        return "sidewalk"
    if facts.on_drivable[0]:
        return "road"
    return "unknown" if not (ctx.map_ctx.has_drivable and ctx.map_ctx.has_sidewalks) else "off-road"


def _settle(ctx: _Context, spot: _Spot) -> PlacedPose:
    """Apply the category rules to a candidate spot (module docstring)."""
    area = _where(ctx, spot.xy, spot.heading)
    if ctx.kind != VEHICLE:
        if area == "off-road":
            raise _refuse(f"cannot place {ctx.noun} {spot.phrase}: that spot is off the road and the sidewalk")
        if spot.area is not None and not box_within(spot.xy, spot.heading, ctx.size,
                                                    area_polygons(ctx.map_ctx, spot.area)):
            raise _refuse(f"cannot place {ctx.noun} {spot.phrase}: it does not fit on the {spot.area} there")
        return PlacedPose(spot.xy, spot.heading, None, area=area)
    lanes = ctx.lanes
    if area == "sidewalk":
        raise _refuse(f"cannot place {ctx.noun} on the sidewalk ({spot.phrase}): vehicles go in lanes")
    if ctx.parked_anchor and spot.side in ("behind", "in_front_of"):
        return _parked_in_line(ctx, spot)
    if lanes is None or not len(lanes):
        raise _refuse(f"cannot place {ctx.noun} {spot.phrase}: this map has no lanes")
    pref = spot.heading if ctx.placement.relation != "absolute" or ctx.hint is not None else None
    m = lanes.nearest(spot.xy[None], None if pref is None else np.array([pref]), align_deg=60.0,
                      max_dist_m=LANE_SNAP_M)
    if m.lane[0] < 0:
        m = lanes.nearest(spot.xy[None], max_dist_m=LANE_SNAP_M)
    if m.lane[0] < 0:
        where = {"road": "on the road but in no lane", "crosswalk": "on a crosswalk but in no lane",
                 "off-road": "off the road"}.get(area, "in no lane")
        if spot.side in ("left_of", "right_of"):
            raise _refuse(f"no lane {spot.phrase} for {ctx.noun} (that spot is {where})")
        raise _refuse(f"cannot place {ctx.noun} {spot.phrase}: that spot is {where}")
    ln = lanes.lanes[int(m.lane[0])]
    s = float(m.s[0])
    xy = np.array([np.interp(s, ln.s, ln.points[:, c]) for c in range(2)])
    heading = float(ln.heading_at(s))
    if spot.side is not None and not _on_side(ctx, spot.side, xy, heading):
        raise _refuse(f"no lane {spot.phrase} for {ctx.noun}")
    return PlacedPose(xy, heading, LaneMatch(m.lane.copy(), m.s.copy(), np.zeros(1), np.zeros(1)), area="lane")


def _parked_in_line(ctx: _Context, spot: _Spot) -> PlacedPose:
    """A vehicle behind / in front of an anchor parked off the lanes: parked at ``spot`` on the anchor's heading
    line, when its whole box is on the drivable area, off the sidewalks, crosswalks and junctions, and clear of
    the anchor."""
    mc = ctx.map_ctx
    if not box_within(spot.xy, spot.heading, ctx.size, mc.drivable):
        raise _refuse(f"cannot place {ctx.noun} {spot.phrase} (parked in line with it): that spot is off the road")
    points = box_points(spot.xy, spot.heading, ctx.size)
    facts = mc.facts(points, np.full(len(points), spot.heading))
    for inside, what in ((facts.on_sidewalk, "on the sidewalk"), (facts.in_crosswalk, "on a crosswalk"),
                         (facts.at_intersection, "in the junction")):
        if inside.any():
            raise _refuse(f"cannot place {ctx.noun} {spot.phrase} (parked in line with it): that spot is {what}")
    assert spot.side is not None
    if not _on_side(ctx, spot.side, spot.xy, spot.heading):
        raise _refuse(f"no room for {ctx.noun} {spot.phrase}")
    return PlacedPose(spot.xy, spot.heading, None, area="road", parked=True)


def _on_side(ctx: _Context, side: str, xy: np.ndarray, heading: float) -> bool:
    """The box at ``(xy, heading)`` lies on ``side`` of the anchor and clear of it."""
    a = ctx.anchor
    rel = xy - a.xy
    if footprints_overlap(a.xy[None], np.array([a.heading]), a.size[:2], xy[None], np.array([heading]),
                          ctx.size[:2], margin=0.1)[0]:
        return False
    if side in ("left_of", "right_of"):
        return bool(np.dot(rel, a.left) * (1.0 if side == "left_of" else -1.0) > 0.5)
    return bool(np.dot(rel, a.forward) * (1.0 if side == "in_front_of" else -1.0) > 0.5)


def _step_of(states: AgentStates, frame: int) -> int:
    """The step of ``states`` at log frame ``frame``. Raises ``ValueError`` when it has none."""
    steps = np.flatnonzero(states.frame_idx == frame)
    if not steps.size:
        raise ValueError(f"frame {frame} is not one of the scenario's steps")
    return int(steps[0])


def _blocking(ctx: _Context, xy: np.ndarray, heading: float, occupied: AgentStates | None, frame: int,
              ignore: Sequence[str]) -> list[int]:
    """Rows of ``occupied`` whose box overlaps the placed one at ``frame`` (grown by ``CLEARANCE_M``)."""
    if occupied is None or not occupied.num_agents:
        return []
    k = _step_of(occupied, frame)
    rows = np.array([r for r in range(occupied.num_agents) if occupied.valid[r, k]
                     and occupied.object_ids[r] not in ignore], dtype=np.int64)
    if not rows.size:
        return []
    hit = footprints_overlap(np.broadcast_to(xy, (len(rows), 2)), np.full(len(rows), heading), ctx.size[:2],
                             occupied.xy[rows, k], occupied.heading[rows, k], occupied.size[rows, :2],
                             margin=CLEARANCE_M)
    return [int(r) for r in rows[hit]]


def _clear(ctx: _Context, placed: PlacedPose, spot: _Spot, occupied: AgentStates | None, frame: int,
           ignore: Sequence[str], z: float) -> PlacedPose:
    """``placed`` if nothing overlaps it at ``frame``, else the nearest nudge along its lane / heading that
    keeps every rule; refuses naming the object in the way."""
    blocked = _blocking(ctx, placed.xy, placed.heading, occupied, frame, ignore)
    if not blocked:
        return PlacedPose(placed.xy, placed.heading, placed.lane, z, placed.area, "", placed.parked)
    assert occupied is not None
    first = occupied.object_ids[blocked[0]]
    what = f"{occupied.categories[blocked[0]]} {first!r}" if first != EGO_ID else "the ego vehicle"
    if ctx.placement.distance_m is not None:
        limit = distance_slack(ctx.placement.distance_m)
    else:
        limit = QUEUE_REACH_M if spot.side in ("behind", "in_front_of") else NUDGE_M
    steps = np.arange(NUDGE_STEP_M, limit + NUDGE_STEP_M / 2.0, NUDGE_STEP_M)
    # no distance said: away from the anchor first, then closer to it (still clear of it and on its side)
    away = {"behind": -1.0, "in_front_of": 1.0}.get(spot.side or "", 1.0) if ctx.placement.distance_m is None else 1.0
    deltas = sorted([*steps.tolist(), *(-steps).tolist()], key=lambda d: (abs(d), -d * away))
    along = _nudger(ctx, placed, spot.side, limit)
    for d in deltas:
        xy, heading = along(d)
        try:
            moved = _settle(ctx, _Spot(xy, heading, spot.phrase, spot.side, spot.area))
        except EditRefused:
            continue
        if spot.side in ("behind", "in_front_of") and not _on_side(ctx, spot.side, moved.xy, moved.heading):
            continue
        if spot.area is not None and not _ahead_within_slack(ctx, moved.xy):
            continue
        if not _blocking(ctx, moved.xy, moved.heading, occupied, frame, ignore):
            word = "ahead" if d > 0 else "back"
            return PlacedPose(moved.xy, moved.heading, moved.lane, z, moved.area,
                              f"nudged {abs(d):.1f} m {word} to clear {what}", moved.parked)
    raise _refuse(f"cannot place {ctx.noun} {spot.phrase}: the spot is taken by {what} at frame {frame} "
                  f"(no free spot within {limit:.0f} m)")


def _ahead_within_slack(ctx: _Context, xy: np.ndarray) -> bool:
    """Whether ``xy`` is still a said distance ahead of the anchor within :func:`distance_slack` (no distance: yes)."""
    distance = ctx.placement.distance_m
    if distance is None:
        return True
    return bool(abs(float(np.dot(xy - ctx.anchor.xy, ctx.anchor.forward)) - distance) <= distance_slack(distance))


def _nudger(ctx: _Context, placed: PlacedPose, side: str | None,
            reach: float) -> Callable[[float], tuple[np.ndarray, float]]:
    """``d -> (xy, heading)``: ``d`` metres (``|d| <= reach``) along the placed object's lane, else along the
    anchor's heading line (behind / in front of it), else along its own heading."""
    if placed.lane is not None and ctx.lanes is not None:
        lp = ctx.lanes.follow(placed.xy, placed.heading, "straight", max_length_m=reach + 20.0)

        def along_lane(d: float) -> tuple[np.ndarray, float]:
            return lp.path.position(lp.start_s + d), float(lp.path.heading(lp.start_s + d))

        return along_lane
    along_line = side in ("behind", "in_front_of")
    forward = ctx.anchor.forward if along_line else np.array([np.cos(placed.heading), np.sin(placed.heading)])

    def along_heading(d: float) -> tuple[np.ndarray, float]:
        return placed.xy + d * forward, placed.heading

    return along_heading


def place_row(first: PlacedPose, *, count: int, spacing_m: float, size: Sequence[float],
              lanes: LaneGraph | None) -> list[PlacedPose]:
    """``count`` objects in a row starting at ``first``, ``spacing_m`` between boxes, along ``first``'s lane
    (or heading): ``[first, second, ...]`` (a row of cones)."""
    step = float(size[0]) + spacing_m
    out = [first]
    if first.lane is not None and lanes is not None:
        lp = lanes.follow(first.xy, first.heading, "straight", max_length_m=step * count + 20.0)
        for k in range(1, count):
            s = lp.start_s + k * step
            out.append(PlacedPose(lp.path.position(s), float(lp.path.heading(s)), None, first.z, first.area,
                                  parked=first.parked))
        return out
    forward = np.array([np.cos(first.heading), np.sin(first.heading)])
    out += [PlacedPose(first.xy + k * step * forward, first.heading, None, first.z, first.area, parked=first.parked)
            for k in range(1, count)]
    return out


def _area_kind_ok(map_ctx: MapContext, xy: np.ndarray, heading: float, area: str) -> bool:
    """Whether a row member at ``xy`` stands on the same kind of map area as the row's first (``area``)."""
    if area not in ("lane", "road", "sidewalk", "crosswalk") or not map_ctx.has_drivable:
        return True
    facts = map_ctx.facts(np.asarray(xy, np.float64)[None], np.array([heading]))
    if area == "sidewalk":
        return bool(facts.on_sidewalk[0])
    if area == "crosswalk":
        return bool(facts.in_crosswalk[0])
    return bool(facts.on_drivable[0] and not facts.on_sidewalk[0])


def row_blockers(row: Sequence[PlacedPose], size: Sequence[float], occupied: AgentStates | None,
                 frame: int) -> list[tuple[int, int]]:
    """``[(member, agent row)]``: the members of a placed row whose box (grown by :data:`CLEARANCE_M`) overlaps an
    agent of ``occupied`` valid at ``frame``."""
    if occupied is None or not occupied.num_agents:
        return []
    k = _step_of(occupied, frame)
    rows = np.flatnonzero(occupied.valid[:, k])
    out = []
    for m, pose in enumerate(row):
        hit = footprints_overlap(np.broadcast_to(pose.xy, (len(rows), 2)), np.full(len(rows), pose.heading),
                                 np.asarray(size, np.float64)[:2], occupied.xy[rows, k], occupied.heading[rows, k],
                                 occupied.size[rows, :2], margin=CLEARANCE_M)
        out += [(m, int(r)) for r in rows[hit]]
    return out


def row_shifter(first: PlacedPose, lanes: LaneGraph | None, reach: float) -> Callable[[float], PlacedPose]:
    """``d -> PlacedPose``: ``first`` moved ``d`` metres (``|d| <= reach``) along its lane (or its heading when it is
    not in a lane), note and flags kept."""
    if first.lane is not None and lanes is not None:
        lp = lanes.follow(first.xy, first.heading, "straight", max_length_m=reach + 20.0)

        def along_lane(d: float) -> PlacedPose:
            s_new = lp.start_s + d
            return PlacedPose(lp.path.position(s_new), float(lp.path.heading(s_new)), first.lane, first.z,
                              first.area, first.note, first.parked)

        return along_lane
    forward = np.array([np.cos(first.heading), np.sin(first.heading)])

    def along_heading(d: float) -> PlacedPose:
        return PlacedPose(first.xy + d * forward, first.heading, None, first.z, first.area, first.note, first.parked)

    return along_heading


def shift_row(row: Sequence[PlacedPose], d: float, *, spacing_m: float, size: Sequence[float],
              lanes: LaneGraph | None, map_ctx: MapContext, occupied: AgentStates | None, frame: int, why: str,
              keep_area: str | None = None) -> list[PlacedPose]:
    """The placed ``row`` (``place_row`` with ``spacing_m``) moved ``d`` metres along its first member's lane (or
    heading), its first member's note saying so and ``why``; ``EditRefused`` when a member would then overlap an
    agent at ``frame`` or stand off ``keep_area`` (default: the first member's surface, the road for a lane,
    road or crosswalk)."""
    first = row[0]
    area = keep_area if keep_area is not None else ("road" if first.area in ("lane", "crosswalk") else first.area)
    moved = place_row(row_shifter(first, lanes, abs(d))(d), count=len(row), spacing_m=spacing_m, size=size,
                      lanes=lanes)
    if row_blockers(moved, size, occupied, frame) or not all(
            _area_kind_ok(map_ctx, p.xy, p.heading, area) for p in moved):
        raise _refuse(f"no room {abs(d):.1f} m {'ahead' if d > 0 else 'back'} of the asked spot")
    return _noted(moved, first.note, f"placed {abs(d):.1f} m {'further ahead' if d > 0 else 'further back'} {why}")


def _noted(row: list[PlacedPose], before: str, note: str) -> list[PlacedPose]:
    """``row`` with its first member's note ``before; note``."""
    head = row[0]
    row[0] = PlacedPose(head.xy, head.heading, head.lane, head.z, head.area, f"{before}; {note}" if before else note,
                        head.parked)
    return row


def place_clear_row(first: PlacedPose, *, count: int, spacing_m: float, size: Sequence[float],
                    lanes: LaneGraph | None, map_ctx: MapContext, occupied: AgentStates | None, frame: int,
                    reach: float = NUDGE_M, category: str = STATIC) -> list[PlacedPose]:
    """:func:`place_row` with every member clear of the agents at ``frame`` (the first was checked by
    ``resolve_placement``; the others were not): the row as placed, else the whole row shifted along its lane /
    heading by the smallest amount (up to ``reach``, in :data:`NUDGE_STEP_M` steps) that frees every member and
    keeps each on the first's kind of area; else ``EditRefused`` naming the agent in the way of which member."""
    row = place_row(first, count=count, spacing_m=spacing_m, size=size, lanes=lanes)
    blocked = row_blockers(row, size, occupied, frame)
    if count <= 1 or not blocked:
        return row
    assert occupied is not None
    member, agent = blocked[0]
    oid = occupied.object_ids[agent]
    what = "the ego vehicle" if oid == EGO_ID else f"{occupied.categories[agent]} {oid!r}"
    steps = np.arange(NUDGE_STEP_M, reach + NUDGE_STEP_M / 2.0, NUDGE_STEP_M)
    shifted = row_shifter(first, lanes, reach)
    for d in sorted([*steps.tolist(), *(-steps).tolist()], key=lambda x: (abs(x), -x)):
        moved = place_row(shifted(d), count=count, spacing_m=spacing_m, size=size, lanes=lanes)
        if row_blockers(moved, size, occupied, frame):
            continue
        if not all(_area_kind_ok(map_ctx, p.xy, p.heading, first.area) for p in moved):
            continue
        return _noted(moved, first.note, f"row shifted {abs(d):.1f} m {'ahead' if d > 0 else 'back'} to clear {what}")
    raise _refuse(f"cannot place a row of {count} {_NOUNS[kind_of(category)][2:]}s there: member {member + 1} "
                  f"overlaps {what} at frame {frame} (no shift of the row within {reach:.0f} m clears every member)")


def footprint(pose: PlacedPose, size: Sequence[float]) -> np.ndarray:
    """``[4, 2]`` corners of the placed box (for pictures and checks)."""
    return box_footprints(pose.xy, np.asarray(pose.heading), np.asarray(size, dtype=np.float64)[:2])
