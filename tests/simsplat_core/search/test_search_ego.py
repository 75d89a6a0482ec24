"""Search with the ego as a subject or relation object, our lane along the ego's route, cut-ins, counts, halts."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.geometry import pose_from_yaw
from simsplat_core.language.grounding.scoring import color_fit
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.search import parse_description, search_log
from simsplat_core.search.describe import FOLLOWING
from simsplat_core.search.engine import SearchConfig
from simsplat_core.search.frames import EGO_ID, EgoPath, ObjectFrames, log_frames, mark_halts
from simsplat_core.types import ObjectInfo, SceneLog
from simsplat_core.viz.contact_sheet import HIGHLIGHT_COLOR, bev_panel
from tests.simsplat_core.search.test_search import FPS, F, _track


def _left_turn(n: int, start: int) -> tuple[np.ndarray, np.ndarray]:
    """Drives +x at 8 m/s, turns left (90 degrees) over frames ``start`` to ``start + 15``, then drives +y."""
    heading = np.zeros(n)
    heading[start: start + 16] = np.linspace(0, np.pi / 2, 16)
    heading[start + 16:] = np.pi / 2
    xy = np.cumsum(0.8 * np.c_[np.cos(heading), np.sin(heading)], axis=0)
    return xy, heading


@pytest.fixture(scope="module")
def ego_log() -> SceneLog:
    """The ego turns left in frames 20-35; a car tails it 10 m behind on its route; a car is parked on the route
    round the corner; a car cuts in from the left lane ahead of the ego in frames 0-8; two pedestrians walk side by
    side on the right, a third alone far off."""
    xy, heading = _left_turn(F + 13, 33)
    ego_xy, ego_h = xy[13:], heading[13:]  # the ego is 13 frames (10.4 m) ahead of its tail
    poses = np.stack([pose_from_yaw(x, y, 0.0, h) for (x, y), h in zip(ego_xy, ego_h)])
    cut_x = ego_xy[0, 0] + 6.0 + np.arange(F) * 1.0
    cut_y = np.clip(3.5 - np.arange(F) * 0.45, 0.0, None)
    walk = np.arange(F) * 0.12
    tracks = (
        _track("veh_tail", xy[:F], heading[:F]),
        _track("veh_parked", np.tile(ego_xy[F - 4], (F, 1)), np.full(F, np.pi / 2)),
        _track("veh_cut", np.c_[cut_x, cut_y], np.zeros(F)),
        _track("ped_a", np.c_[walk, np.full(F, -8.0)], np.zeros(F)),
        _track("ped_b", np.c_[walk, np.full(F, -9.0)], np.zeros(F)),
        _track("ped_c", np.c_[walk - 30.0, np.full(F, 40.0)], np.zeros(F)),
    )
    objects = tuple(ObjectInfo(t.object_id, "pedestrian" if t.object_id.startswith("ped") else "vehicle",
                               "nonrigid" if t.object_id.startswith("ped") else "rigid", k + 1, "", {})
                    for k, t in enumerate(tracks))
    return SceneLog("ego", "synthetic", (np.arange(F) * 1e6 / FPS).astype(np.int64), poses, (), tracks, objects,
                    (), {}).validate()


@pytest.fixture(scope="module")
def objects(ego_log: SceneLog) -> dict[str, ObjectFrames]:
    return log_frames(ego_log)


def test_ego_wording_parses() -> None:
    (ego,) = parse_description("while we turn left").clauses
    assert ego.is_ego and ego.motions == (voc.TURNING_LEFT,)
    car, ego2 = parse_description("a car turning right while we turn left").clauses
    assert not car.is_ego and ego2.is_ego
    (slow,) = parse_description("as our car slows down").clauses
    assert slow.is_ego and set(slow.motions) == {voc.SLOWING_DOWN, voc.STOPPING}  # a halt is a slow-down
    (stop,) = parse_description("when the ego is stopped at the intersection").clauses
    assert stop.is_ego and stop.motions == (voc.STOPPED,) and stop.contexts == (voc.AT_THE_INTERSECTION,)
    (tail,) = parse_description("a car following us").clauses
    assert tail.relation == FOLLOWING and tail.related is not None and tail.related.is_ego
    assert not parse_description("the ego lane blocked by a parked truck").clauses[0].is_ego
    assert parse_description("a vehicle cutting in front of us").clauses[0].cut_in
    (two,) = parse_description("two pedestrians walking together").clauses
    assert two.count == 2 and two.together
    (truck,) = parse_description("Where does a truck turn left?").clauses
    assert truck.parsed.subtype == "truck" and truck.motions == (voc.TURNING_LEFT,)


@pytest.mark.parametrize("text", ["While we turn left, a pedestrian waits on the sidewalk.",
                                  "while we turn left at the intersection a pedestrian waits on the sidewalk",
                                  "as we turn left a pedestrian waits on the sidewalk"])
def test_a_description_opening_with_its_while_clause_is_read_like_one_ending_with_it(text: str) -> None:
    ped, ego = parse_description(text).clauses
    assert ped.text == "a pedestrian waits on the sidewalk" and not ped.is_ego
    assert ego.is_ego and ego.motions == (voc.TURNING_LEFT,)
    car, ped2 = parse_description("while a car following the bus slows down, a pedestrian crosses").clauses[::-1]
    assert car.relation == FOLLOWING and ped2.text == "a pedestrian crosses"


def test_the_ego_turn_is_found_where_it_happens(objects: dict[str, ObjectFrames]) -> None:
    result = search_log("ego", objects, F, "while we turn left")
    assert [h.object_ids for h in result.hits] == [(EGO_ID,)]
    start, end = result.hits[0].window
    assert 14 <= start <= 22 and 33 <= end <= 41  # the turn is frames 20-35; windows are +-1 s
    assert search_log("ego", objects, F, "while we turn right").hits == ()
    turning = search_log("ego", objects, F, "a car turning left").hits  # the ego is no "car" of other clauses
    assert turning and all(EGO_ID not in h.object_ids for h in turning)


def test_relations_to_the_ego(objects: dict[str, ObjectFrames]) -> None:
    tail = search_log("ego", objects, F, "a car following us")
    assert tail.hits and tail.hits[0].object_ids == ("veh_tail", EGO_ID)
    cut = search_log("ego", objects, F, "a vehicle cutting in front of us")
    assert [h.object_ids for h in cut.hits] == [("veh_cut",)] and cut.hits[0].window[0] <= 5


def test_our_lane_follows_the_route_round_the_corner(objects: dict[str, ObjectFrames]) -> None:
    parked = objects["veh_parked"]
    assert parked.lane_along[10] == pytest.approx(36 * 0.8, abs=0.5) and abs(parked.lane_offset[10]) < 1.0
    assert abs(parked.xy_ego[10, 1]) > 5.0  # a straight box ahead of the ego would miss it
    result = search_log("ego", objects, F, "a car blocking our lane")
    assert [h.object_ids for h in result.hits] == [("veh_parked",)]


def test_counts(objects: dict[str, ObjectFrames]) -> None:
    two = search_log("ego", objects, F, "two pedestrians walking together")
    assert two.hits and set(two.hits[0].object_ids) == {"ped_a", "ped_b"}
    three = search_log("ego", objects, F, "three pedestrians walking together")
    assert three.hits == () and "never 3 objects together" in three.message


def test_ego_path_coordinates() -> None:
    poses = np.stack([pose_from_yaw(float(x), 0.0, 0.0, 0.0) for x in range(5)])
    along, offset = EgoPath(poses, ahead_m=20.0).locate(1, np.array([[3.0, 1.0], [10.0, -2.0], [0.0, 0.5]]))
    assert along.tolist() == pytest.approx([2.0, 9.0, -1.0]) and offset.tolist() == pytest.approx([1.0, -2.0, 0.5])


def test_a_halt_is_stopping_over_the_whole_braking() -> None:
    motion = np.array([voc.GOING_STRAIGHT, voc.SLOWING_DOWN, voc.SLOWING_DOWN, voc.STOPPING, voc.STOPPING,
                       voc.STOPPED, voc.SLOWING_DOWN], dtype=object)
    speed = np.array([8.0, 6.0, 4.0, 2.0, 0.1, 0.0, 5.0])
    assert mark_halts(motion, speed).tolist() == [voc.GOING_STRAIGHT, voc.STOPPING, voc.STOPPING, voc.STOPPING,
                                                  voc.STOPPED, voc.STOPPED, voc.SLOWING_DOWN]


def test_a_named_colour_wants_the_caption_colour_not_a_neighbour() -> None:
    cfg = SearchConfig()
    assert color_fit("purple", "blue", cfg.query) < cfg.min_appearance <= color_fit("purple", "purple", cfg.query)


def test_bev_picture_highlights_the_hit(ego_log: SceneLog) -> None:
    plain = bev_panel(ego_log, 25)
    marked = bev_panel(ego_log, 25, highlight=("veh_tail",), window=(20, 30), highlight_ego=True)
    magenta = np.all(marked == HIGHLIGHT_COLOR, axis=-1)
    assert magenta.sum() > 20 and not np.all(plain == HIGHLIGHT_COLOR, axis=-1).any()
