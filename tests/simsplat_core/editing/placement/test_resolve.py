"""Placement resolution on the synthetic intersection (seed 0: the ego drives +x in the right lane of a
two-lane road) and on the real AV2 map: lanes, sides, distances, map areas, occupancy, refusals."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.editing.commands import Placement
from simsplat_core.editing.placement.resolve import (
    LANE_AHEAD_M,
    LONG_GAP_M,
    AnchorPose,
    PlacedPose,
    distance_slack,
    footprint,
    place_row,
    resolve_placement,
    shift_row,
)
from simsplat_core.editing.result import EditRefused
from simsplat_core.geometry import pose_from_yaw
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.geometry import footprints_overlap, points_in_polygon, signed_polygon_distance
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.world import WorldConfig, generate_log, layout_from_log

CAR = (4.5, 1.9, 1.5)
PERSON = (0.6, 0.6, 1.8)
CONE = (0.4, 0.4, 0.7)
AV2_LOG = Path("av2") / "sensor-log-7fab2350"


@pytest.fixture(scope="module")
def world():
    log = generate_log(0, WorldConfig(render_images=False))
    return {"log": log, "layout": layout_from_log(log), "ctx": MapContext.from_features(log.map_features),
            "lanes": LaneGraph.from_features(log.map_features), "states": AgentStates.from_log(log)}


def _place(world, placement: Placement, category: str = "vehicle", size=CAR, anchor: AnchorPose | None = None,
           frame: int = 0, occupied: AgentStates | None = None, crossing: bool = False) -> PlacedPose:
    extra = {"crossing": True} if crossing else {}
    return resolve_placement(placement, category=category, size=size, anchor=anchor,
                             ego_pose=world["log"].ego_poses[frame], lanes=world["lanes"], map_ctx=world["ctx"],
                             frame=frame, occupied=occupied, **extra)


def _lane_id(world, pose: PlacedPose) -> str:
    assert pose.lane is not None
    return world["lanes"].lanes[int(pose.lane.lane[0])].lane_id


def _refused(world, placement: Placement, words: str, **kw) -> EditRefused:
    with pytest.raises(EditRefused, match=words) as err:
        _place(world, placement, **kw)
    assert err.value.reason == "infeasible_placement"
    return err.value


def _empty_anchor(world, xy, heading: float, category: str = "vehicle", size=CAR) -> AnchorPose:
    return AnchorPose(np.asarray(xy, float), heading, size, category, "anchor_1", size[2] / 2.0, "the white van")


def _ego_only(world) -> AgentStates:
    """The scenario's steps with the ego as the only agent."""
    st = world["states"]
    return st.take([st.index("ego")])


def _with_box(states: AgentStates, object_id: str, category: str, xy, heading: float, size) -> AgentStates:
    """``states`` plus an agent standing at ``xy`` over every step."""
    n = states.num_steps
    return states.with_agent(object_id, category, "log", xy=np.tile(np.asarray(xy, float), (n, 1)),
                             heading=np.full(n, heading), speed=np.zeros(n), valid=np.ones(n, bool), size=size)


def _ahead(world, xy, frame: int = 0) -> np.ndarray:
    """``[2]`` (ahead, left) of a world point in the ego frame."""
    return (np.linalg.inv(world["log"].ego_poses[frame]) @ np.r_[np.asarray(xy, float), 0.0, 1.0])[:2]


def _inside(world, area: str, pose: PlacedPose, size) -> bool:
    polys = {"sidewalk": world["ctx"].sidewalks, "road": world["ctx"].drivable}[area]
    corners = np.vstack([pose.xy[None], footprint(pose, size)])
    return bool(all(any(points_in_polygon(c[None], poly)[0] for poly in polys) for c in corners))


# ------------------------------------------------------------------------------------------ lanes
def test_in_lane_placements_follow_the_lane_graph(world) -> None:
    layout = world["layout"]
    width = layout.lane_w("W")
    ego_y = world["log"].ego_poses[0][1, 3]  # the ego drives the right (outer) lane, +x
    same = _place(world, Placement(relation="in_lane", lane="same", distance_m=20.0))
    assert same.xy == pytest.approx([20.0, ego_y], abs=0.05) and same.heading == pytest.approx(0.0, abs=1e-3)
    assert same.area == "lane" and _lane_id(world, same).endswith("_1") and same.z == pytest.approx(CAR[2] / 2)
    left = _place(world, Placement(relation="in_lane", lane="left", distance_m=20.0))
    assert left.xy == pytest.approx([20.0, ego_y + width], abs=0.05) and left.heading == pytest.approx(0.0, abs=1e-3)
    oncoming = _place(world, Placement(relation="in_lane", lane="opposite", distance_m=30.0))
    assert oncoming.xy[0] == pytest.approx(30.0, abs=0.6) and oncoming.xy[1] > ego_y + 1.5 * width
    assert abs(abs(oncoming.heading) - np.pi) < 1e-3  # facing the ego
    default = _place(world, Placement(relation="in_lane"))
    assert default.xy[0] == pytest.approx(LANE_AHEAD_M, abs=0.05)
    err = _refused(world, Placement(relation="in_lane", lane="right"), "no lane to the right of the ego vehicle")
    assert "right" in str(err)


def test_a_car_beside_its_anchor_lands_in_the_lane_on_that_side(world) -> None:
    layout = world["layout"]
    width = layout.lane_w("W")
    ego_y = world["log"].ego_poses[0][1, 3]
    left = _place(world, Placement(relation="left_of"))
    assert left.xy == pytest.approx([0.0, ego_y + width], abs=0.05) and left.area == "lane"
    ahead = _place(world, Placement(relation="in_front_of", distance_m=5.0))
    assert ahead.xy[1] == pytest.approx(ego_y, abs=0.05)
    assert ahead.xy[0] - CAR[0] / 2 - 4.8 / 2 == pytest.approx(5.0, abs=0.05)  # 5 m between the bumpers
    behind = _place(world, Placement(relation="behind"))
    assert behind.xy[0] < -4.0 and behind.xy[1] == pytest.approx(ego_y, abs=0.05)
    # the ego's right is the kerbside parking strip: no lane there
    _refused(world, Placement(relation="right_of"), "no lane to the right of the ego vehicle")
    # next_to: right first, else left
    beside = _place(world, Placement(relation="next_to"))
    assert beside.xy == pytest.approx(left.xy, abs=1e-6)


def test_people_and_objects_beside_an_anchor_keep_the_gap(world) -> None:
    layout = world["layout"]
    van_xy = layout.arm_point("W", 50.0, layout.lane_offset("W", True, 0))
    van = _empty_anchor(world, van_xy, 0.0, size=(5.5, 2.1, 2.4))
    person = _place(world, Placement(relation="right_of", distance_m=2.0), "pedestrian", PERSON, anchor=van)
    assert person.xy[1] - van_xy[1] == pytest.approx(-(2.1 / 2 + 2.0 + PERSON[1] / 2))
    assert person.xy[0] == pytest.approx(van_xy[0]) and person.area == "road"  # in the next lane
    _refused(world, Placement(relation="in_lane", lane="left"), "no lane to the left of the white van", anchor=van)
    oncoming = _place(world, Placement(relation="left_of"), anchor=van)  # left of the inner lane: oncoming traffic
    assert oncoming.xy[1] - van_xy[1] == pytest.approx(layout.lane_w("W"), abs=0.05)
    assert abs(abs(oncoming.heading) - np.pi) < 1e-3
    cone = _place(world, Placement(relation="behind"), "static", CONE, anchor=van)
    assert van_xy[0] - cone.xy[0] == pytest.approx(5.5 / 2 + 3.0 + CONE[0] / 2)
    # the z follows the anchor's ground
    assert cone.z == pytest.approx(van.z - 2.4 / 2 + CONE[2] / 2)


# ------------------------------------------------------------------------------------------ map areas
def test_map_area_rules_per_category(world) -> None:
    ctx = world["ctx"]
    _refused(world, Placement(relation="on_sidewalk"), "cannot place a car on the sidewalk")
    walker = _place(world, Placement(relation="on_sidewalk"), "pedestrian", PERSON)
    corners = footprint(walker, PERSON)
    assert walker.area == "sidewalk"
    assert any(points_in_polygon(corners, poly).all() for poly in ctx.sidewalks)
    crossing = _place(world, Placement(relation="on_crosswalk"), "pedestrian", PERSON)
    assert crossing.area == "crosswalk" and ctx.facts(crossing.xy[None], np.zeros(1)).in_crosswalk[0]
    assert abs(np.sin(crossing.heading)) > 0.99  # along the crosswalk, across the road
    car_on_cw = _place(world, Placement(relation="on_crosswalk"))
    assert car_on_cw.area == "lane" and ctx.facts(car_on_cw.xy[None], np.zeros(1)).in_crosswalk[0]
    assert car_on_cw.heading == pytest.approx(0.0, abs=1e-3)  # in a lane running the ego's way
    cone = _place(world, Placement(relation="on_road", distance_m=15.0), "static", CONE)
    assert cone.xy == pytest.approx([15.0, 0.0], abs=0.05) and cone.area == "road"
    # a car "at" a spot on the sidewalk (absolute, 11 m to the ego's right) is refused; a person may go there
    _refused(world, Placement(relation="absolute", position=(5.0, -6.0, 0.0)), "cannot place a car on the sidewalk")
    assert _place(world, Placement(relation="absolute", position=(5.0, -6.0, 0.0)), "pedestrian",
                  PERSON).area == "sidewalk"
    _refused(world, Placement(relation="absolute", position=(5.0, -30.0, 0.0)), "off the road and the sidewalk",
             category="pedestrian", size=PERSON)


def test_absolute_positions_are_in_the_ego_frame_at_the_frame(world) -> None:
    log = world["log"]
    frame = 39  # the ego has turned by then
    ego = log.ego_poses[frame]
    yaw = np.arctan2(ego[1, 0], ego[0, 0])
    cone = _place(world, Placement(relation="absolute", position=(8.0, 0.0, 0.0), heading_deg=90.0, frame=frame),
                  "static", CONE, frame=frame)
    np.testing.assert_allclose(cone.xy, (ego @ np.array([8.0, 0.0, 0.0, 1.0]))[:2])
    assert np.angle(np.exp(1j * (cone.heading - yaw - np.pi / 2))) == pytest.approx(0.0, abs=1e-9)
    assert cone.z == pytest.approx(ego[2, 3] + CONE[2] / 2)
    car = _place(world, Placement(relation="absolute", position=(10.0, 0.3, 0.0), frame=frame), frame=frame)
    m = world["lanes"].nearest(car.xy[None])
    assert m.distance[0] < 1e-6 and car.area == "lane"  # snapped onto the lane, along it
    assert abs(np.angle(np.exp(1j * (car.heading - yaw)))) < np.deg2rad(30)


# ------------------------------------------------------------------------------------------ occupancy
def test_occupied_spots_are_nudged_or_refused_naming_the_object(world) -> None:
    st = world["states"]
    row = next(r for r in range(1, st.num_agents) if st.categories[r] == "vehicle" and st.valid[r, 0])
    other = st.object_ids[row]
    xy, h = st.xy[row, 0], st.heading[row, 0]
    ego = world["log"].ego_poses[0]
    local = np.linalg.inv(ego) @ np.r_[xy, 0.0, 1.0]
    on_top = Placement(relation="absolute", position=(float(local[0]), float(local[1]), 0.0))
    err = _refused(world, on_top, f"the spot is taken by vehicle '{other}' at frame 0", occupied=st)
    assert "no free spot within" in str(err)
    # a spot half a car length off is nudged clear along the lane, and says so
    lane_dir = np.array([np.cos(h), np.sin(h)])
    near = xy + 0.6 * st.size[row, 0] * lane_dir + 0.2 * np.array([-lane_dir[1], lane_dir[0]])
    local = np.linalg.inv(ego) @ np.r_[near, 0.0, 1.0]
    nudged = _place(world, Placement(relation="absolute", position=(float(local[0]), float(local[1]), 0.0)),
                    occupied=st)
    assert other in nudged.note and "nudged" in nudged.note
    assert not footprints_overlap(nudged.xy[None], np.array([nudged.heading]), CAR[:2], xy[None], np.array([h]),
                                  st.size[row, :2])[0]
    # without occupancy the same spot is taken as is
    assert _place(world, Placement(relation="absolute", position=(float(local[0]), float(local[1]), 0.0))).note == ""


# ------------------------------------------------------------------------------------------ parked anchors
def _parked_anchor(world, s: float) -> AnchorPose:
    """A car parked in the ego's kerbside parking strip (west arm, facing east like the ego), ``s`` m from the
    junction."""
    layout = world["layout"]
    xy = layout.arm_point("W", s, layout.parking_offset("W", True))
    return AnchorPose(xy, 0.0, CAR, "vehicle", "parked_1", CAR[2] / 2.0, "the parked hatchback")


def test_a_car_behind_or_in_front_of_a_parked_car_parks_in_line_with_it(world) -> None:
    parked = _parked_anchor(world, 40.0)
    assert world["lanes"].nearest(parked.xy[None], max_dist_m=2.5).lane[0] < 0  # the strip is in no lane
    behind = _place(world, Placement(relation="behind"), anchor=parked, occupied=_ego_only(world))
    ahead = _place(world, Placement(relation="in_front_of", distance_m=8.0), anchor=parked)
    for pose, sign, gap in ((behind, -1.0, LONG_GAP_M), (ahead, 1.0, 8.0)):
        rel = pose.xy - parked.xy
        assert pose.parked and pose.lane is None and pose.area == "road"
        assert rel[1] == pytest.approx(0.0, abs=1e-6) and pose.heading == pytest.approx(parked.heading)
        assert sign * rel[0] == pytest.approx(CAR[0] + gap)  # bumper to bumper
        assert _inside(world, "road", pose, CAR)
    # a car beside the parked one still goes into the lane next to it
    assert not _place(world, Placement(relation="left_of"), anchor=parked).parked
    # a car driving there is not parked: nothing parks behind it
    _refused(world, Placement(relation="behind"), "in no lane", anchor=dataclasses.replace(parked, speed=5.0))


def test_a_car_in_line_with_a_parked_car_is_refused_off_the_road_or_where_taken(world) -> None:
    layout = world["layout"]
    near_end = _parked_anchor(world, layout.arm_length - CAR[0])
    _refused(world, Placement(relation="behind"), "off the road", anchor=near_end)
    # the strip ends at the junction: no parking on the crosswalk in front of the first parked car
    first = _parked_anchor(world, layout.crosswalk_range("W")[1] + CAR[0])
    _refused(world, Placement(relation="in_front_of"), "crosswalk|junction", anchor=first)
    parked = _parked_anchor(world, 40.0)
    spot = _place(world, Placement(relation="behind"), anchor=parked)
    # a van in the way over a long stretch behind: nothing free within the nudge
    taken = _with_box(_ego_only(world), "van_9", "vehicle", spot.xy + np.array([-4.0, 0.0]), 0.0, (14.0, 2.0, 2.5))
    _refused(world, Placement(relation="behind"), "the spot is taken by vehicle 'van_9'", anchor=parked,
             occupied=taken)
    # a cone just behind: nudged further back along the strip, still in line
    cone = _with_box(_ego_only(world), "cone_9", "static", spot.xy + np.array([1.5, 0.0]), 0.0, CONE)
    nudged = _place(world, Placement(relation="behind"), anchor=parked, occupied=cone)
    assert "cone_9" in nudged.note and nudged.parked and nudged.xy[0] < spot.xy[0]
    assert nudged.xy[1] == pytest.approx(parked.xy[1])


def test_behind_an_anchor_with_a_car_queued_behind_it_is_behind_that_car(world) -> None:
    """"Place a car behind the parked car" where another waits 2 m behind it: behind that one (no distance said);
    "3 m behind" it is taken (the said distance cannot be met)."""
    parked = _parked_anchor(world, 40.0)
    spot = _place(world, Placement(relation="behind"), anchor=parked)
    queued = _with_box(_ego_only(world), "car_9", "vehicle", spot.xy, 0.0, CAR)
    behind = _place(world, Placement(relation="behind"), anchor=parked, occupied=queued)
    assert "car_9" in behind.note and behind.xy[0] < spot.xy[0] - CAR[0]
    _refused(world, Placement(relation="behind", distance_m=3.0), "the spot is taken by vehicle 'car_9'",
             anchor=parked, occupied=queued)


# ------------------------------------------------------------------------------------------ crossing pedestrians
def test_a_pedestrian_about_to_cross_starts_at_the_road_edge(world) -> None:
    ctx = world["ctx"]
    parked = _parked_anchor(world, 40.0)
    anchor = AnchorPose(parked.xy + np.array([0.0, world["layout"].parking_w_h / 2 + 2.0]), 0.0, CAR, "vehicle",
                        "car_1", CAR[2] / 2.0, "the red car")  # in the ego's lane
    plain = _place(world, Placement(relation="in_front_of", distance_m=10.0), "pedestrian", PERSON, anchor=anchor)
    at_edge = _place(world, Placement(relation="in_front_of", distance_m=10.0), "pedestrian", PERSON, anchor=anchor,
                     crossing=True)
    assert at_edge.xy[0] == pytest.approx(plain.xy[0])  # as far ahead
    assert at_edge.xy[1] < plain.xy[1]  # towards the kerb on the right, the nearer one
    inside = signed_polygon_distance(at_edge.xy[None], ctx.drivable)[0]
    assert 0.0 < inside <= PERSON[1]  # on the road, right at its edge
    assert np.sin(at_edge.heading) > 0.99  # facing across the road


def test_a_taken_spot_is_searched_along_the_line_within_the_slack_of_the_distance(world) -> None:
    parked = _parked_anchor(world, 40.0)
    anchor = AnchorPose(parked.xy + np.array([0.0, world["layout"].parking_w_h / 2 + 2.0]), 0.0, CAR, "vehicle",
                        "car_1", CAR[2] / 2.0, "the red car")
    ask = Placement(relation="in_front_of", distance_m=20.0)
    free = _place(world, ask, "pedestrian", PERSON, anchor=anchor, crossing=True)
    # a truck parked over the spot and 5 m beyond: more than the 4 m nudge, within the slack of 20 m
    truck = _with_box(_ego_only(world), "truck_9", "vehicle", free.xy + np.array([2.0, 0.0]), 0.0, (10.0, 2.2, 3.0))
    moved = _place(world, ask, "pedestrian", PERSON, anchor=anchor, crossing=True, occupied=truck)
    assert "truck_9" in moved.note and moved.xy[1] == pytest.approx(free.xy[1])
    assert 0.0 < abs(moved.xy[0] - free.xy[0]) <= distance_slack(20.0)
    assert not footprints_overlap(moved.xy[None], np.array([moved.heading]), PERSON[:2], free.xy[None] + [2.0, 0.0],
                                  np.zeros(1), (10.0, 2.2))[0]
    # ... but not beyond it
    long = _with_box(_ego_only(world), "train_9", "vehicle", free.xy, 0.0, (4.0 * distance_slack(20.0), 2.2, 3.0))
    _refused(world, ask, "taken by vehicle 'train_9'", category="pedestrian", size=PERSON, anchor=anchor,
             crossing=True, occupied=long)


# ------------------------------------------------------------------------------------------ areas a distance ahead
@pytest.mark.parametrize(("category", "size", "distance"), [("pedestrian", PERSON, 10.0), ("static", CONE, 15.0)])
def test_on_the_sidewalk_ahead_of_a_junction_lands_on_the_sidewalk_about_that_far(world, category, size,
                                                                                  distance) -> None:
    ctx = world["ctx"]
    query = np.asarray(world["log"].ego_poses[0] @ np.array([distance, 0.0, 0.0, 1.0]))[:2]
    assert ctx.facts(query[None], np.zeros(1)).at_intersection[0]  # straight ahead is the junction
    pose = _place(world, Placement(relation="on_sidewalk", distance_m=distance), category, size)
    ahead, left = _ahead(world, pose.xy)
    assert pose.area == "sidewalk" and _inside(world, "sidewalk", pose, size)
    assert abs(ahead - distance) <= distance_slack(distance) and left < 0  # on the ego's (kerb) side
    # facing along the sidewalk: a straight walk from there stays on it
    walk = pose.xy + np.arange(0.0, 10.0, 0.5)[:, None] * np.array([np.cos(pose.heading), np.sin(pose.heading)])
    assert ctx.facts(walk, np.full(len(walk), pose.heading)).on_sidewalk.all()
    # someone standing there: the object is moved clear, still on the sidewalk
    taken = _with_box(_ego_only(world), "ped_9", "pedestrian", pose.xy, 0.0, PERSON)
    moved = _place(world, Placement(relation="on_sidewalk", distance_m=distance), category, size, occupied=taken)
    assert "ped_9" in moved.note and moved.area == "sidewalk" and _inside(world, "sidewalk", moved, size)
    assert abs(_ahead(world, moved.xy)[0] - distance) <= distance_slack(distance)


def test_no_sidewalk_about_that_far_ahead_is_refused(world) -> None:
    far = 3.0 * world["layout"].arm_length
    _refused(world, Placement(relation="on_sidewalk", distance_m=far), "cannot place a pedestrian on a sidewalk: none",
             category="pedestrian", size=PERSON)


def test_a_row_of_cones_along_the_lane(world) -> None:
    first = _place(world, Placement(relation="in_lane", distance_m=12.0), "static", CONE)
    row = place_row(first, count=4, spacing_m=1.6, size=CONE, lanes=world["lanes"])
    gaps = np.linalg.norm(np.diff(np.array([p.xy for p in row]), axis=0), axis=1)
    np.testing.assert_allclose(gaps, CONE[0] + 1.6, atol=1e-6)
    assert all(abs(p.xy[1] - first.xy[1]) < 1e-6 for p in row)


# ------------------------------------------------------------------------------------------ AV2
@pytest.mark.shared_data
def test_av2_lane_placements(shared_data: Path) -> None:
    from simsplat_core.data import load_av2_log

    log_dir = shared_data / AV2_LOG
    if not log_dir.exists():
        pytest.skip("AV2 sample absent")
    log = load_av2_log(log_dir)
    lanes, ctx = LaneGraph.from_features(log.map_features), MapContext.from_features(log.map_features)
    states = AgentStates.from_log(log)
    placed = 0
    for frame in (0, 50, 100, 150):
        ego = log.ego_poses[frame]
        try:
            pose = resolve_placement(Placement(relation="in_lane", distance_m=20.0), category="vehicle", size=CAR,
                                     anchor=None, ego_pose=ego, lanes=lanes, map_ctx=ctx, frame=frame,
                                     occupied=states)
        except EditRefused as err:  # e.g. the spot is taken: the message names the object
            assert err.reason == "infeasible_placement" and "taken by" in str(err)
            continue
        m = lanes.nearest(pose.xy[None], np.array([pose.heading]), align_deg=10.0)
        assert m.distance[0] < 0.05 and pose.area == "lane"
        ahead = np.linalg.inv(ego) @ np.r_[pose.xy, ego[2, 3], 1.0]
        # 20 m along the ego's lane: straight ahead, or less far as the crow flies where the lane turns
        assert ahead[0] > 5.0 and 12.0 < np.hypot(ahead[0], ahead[1]) <= 20.5
        placed += 1
    assert placed >= 2
    with pytest.raises(EditRefused, match="this map has no sidewalks"):
        resolve_placement(Placement(relation="on_sidewalk"), category="pedestrian", size=PERSON, anchor=None,
                          ego_pose=log.ego_poses[0], lanes=lanes, map_ctx=ctx, frame=0, occupied=None)
    anchor_pose = pose_from_yaw(0.0, 0.0, 0.0, 0.0)
    assert resolve_placement(Placement(relation="on_road", distance_m=10.0), category="static", size=CONE,
                             anchor=None, ego_pose=anchor_pose, lanes=lanes, map_ctx=ctx, frame=0,
                             occupied=None).area == "road"


def test_every_member_of_a_row_gets_room_or_the_row_is_refused(world) -> None:
    """Only the first of a row goes through ``resolve_placement``: the others are checked too. A car standing where
    the third cone would go shifts the whole row clear (every member), a car at either end of every shift
    refuses naming it."""
    from simsplat_core.editing.placement.resolve import place_clear_row, place_row, row_blockers

    ego = _ego_only(world)
    first = _place(world, Placement(relation="in_lane", distance_m=15.0), category="static", size=CONE, occupied=ego)
    plain = place_row(first, count=4, spacing_m=1.5, size=CONE, lanes=world["lanes"])
    third = plain[2]
    blocked = _with_box(ego, "car_9", "vehicle", third.xy, third.heading, CAR)
    assert {m for m, _ in row_blockers(plain, CONE, blocked, 0)} == {1, 2, 3}  # unchecked before: it overlapped
    row = place_clear_row(first, count=4, spacing_m=1.5, size=CONE, lanes=world["lanes"], map_ctx=world["ctx"],
                          occupied=blocked, frame=0, reach=8.0)
    assert len(row) == 4 and not row_blockers(row, CONE, blocked, 0)
    assert "row shifted" in row[0].note and "car_9" in row[0].note
    assert max(abs(float(np.linalg.norm(a.xy - b.xy)) - 1.9) for a, b in zip(row, row[1:])) < 0.05  # still a row
    with pytest.raises(EditRefused, match="member 2 overlaps vehicle 'car_9'") as err:
        place_clear_row(first, count=4, spacing_m=1.5, size=CONE, lanes=world["lanes"], map_ctx=world["ctx"],
                        occupied=blocked, frame=0, reach=1.0)
    assert err.value.reason == "infeasible_placement"
    # nothing in the way: the row as placed
    assert [p.xy.tolist() for p in place_clear_row(first, count=4, spacing_m=1.5, size=CONE, lanes=world["lanes"],
                                                   map_ctx=world["ctx"], occupied=ego, frame=0)] == \
        [p.xy.tolist() for p in plain]


def test_a_row_shifted_for_room_keeps_to_the_road_or_to_the_asked_area(world) -> None:
    """A row of cones starting on a crosswalk may move along onto plain road (a crosswalk is road), but not when
    the crosswalk itself was asked for; a shift onto an agent is refused."""
    ahead = (_place(world, Placement(relation="in_lane", distance_m=d), "static", CONE) for d in range(5, 60))
    first = next(p for p in ahead if p.area == "crosswalk")  # the first spot of the ego lane on a crosswalk
    row = place_row(first, count=3, spacing_m=1.5, size=CONE, lanes=world["lanes"])
    kw = {"spacing_m": 1.5, "size": CONE, "lanes": world["lanes"], "map_ctx": world["ctx"],
          "occupied": _ego_only(world), "frame": 0, "why": "for room"}
    moved = shift_row(row, 6.0, **kw)
    assert np.linalg.norm(moved[0].xy - first.xy) == pytest.approx(6.0, abs=0.3)
    assert "further ahead for room" in moved[0].note
    assert not world["ctx"].facts(moved[0].xy[None], np.array([moved[0].heading])).in_crosswalk[0]
    with pytest.raises(EditRefused, match="no room"):
        shift_row(row, 6.0, **{**kw, "keep_area": "crosswalk"})
    blocked = _with_box(_ego_only(world), "van", "vehicle", moved[1].xy, moved[1].heading, CAR)
    with pytest.raises(EditRefused, match="no room"):
        shift_row(row, 6.0, **{**kw, "occupied": blocked})


def test_a_cone_in_front_of_a_queued_car_with_no_distance_said_may_stand_closer_than_usual(world) -> None:
    """No distance said, a cone goes a usual gap in front of the anchor; when a car stands there (a queue), it
    goes into the gap between the two, closer to the anchor, rather than being refused or put past the car."""
    parked = _parked_anchor(world, 40.0)
    cone = (0.4, 0.4, 0.7)
    free = _place(world, Placement(relation="in_front_of"), "static", cone, anchor=parked, occupied=_ego_only(world))
    gap = float(np.dot(free.xy - parked.xy, [np.cos(parked.heading), np.sin(parked.heading)])) - CAR[0] / 2
    forward = np.array([np.cos(parked.heading), np.sin(parked.heading)])
    queued_xy = parked.xy + forward * (CAR[0] + gap - 0.2)  # its rear bumper just past where the cone would go
    occupied = _with_box(_ego_only(world), "queued", "vehicle", queued_xy, parked.heading, CAR)
    placed = _place(world, Placement(relation="in_front_of"), "static", cone, anchor=parked, occupied=occupied)
    ahead = float(np.dot(placed.xy - parked.xy, forward))
    assert CAR[0] / 2 < ahead < float(np.dot(free.xy - parked.xy, forward)) and "nudged" in placed.note
