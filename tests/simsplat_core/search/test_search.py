"""Search: description parsing, windows on a hand-built log, negatives, metrics against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simsplat_core.eval.search.metrics import balanced_accuracy, log_ba, timestamp_ba
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.search import parse_description, search_log
from simsplat_core.search.describe import FOLLOWING
from simsplat_core.search.frames import log_frames
from simsplat_core.search.windows import covered, frame_windows
from simsplat_core.types import ObjectInfo, SceneLog, Track

F = 50
FPS = 10.0


def _track(oid: str, xy: np.ndarray, heading: np.ndarray) -> Track:
    speed = np.r_[np.linalg.norm(np.diff(xy, axis=0), axis=1) * FPS, 0.0]
    center = np.c_[xy, np.full(len(xy), 0.8)]
    return Track(oid, np.arange(len(xy)), center, np.tile([4.5, 1.9, 1.6], (len(xy), 1)), heading, speed,
                 np.ones(len(xy), dtype=bool))


def _turning_car() -> tuple[np.ndarray, np.ndarray]:
    """Drives +x at 8 m/s, turns right (90 degrees, clockwise) over frames 20-35, then drives -y."""
    heading = np.zeros(F)
    heading[20:36] = -np.linspace(0, np.pi / 2, 16)
    heading[36:] = -np.pi / 2
    step = 0.8 * np.c_[np.cos(heading), np.sin(heading)]
    xy = np.cumsum(step, axis=0) + [10.0, 0.0]
    return xy, heading


@pytest.fixture(scope="module")
def hand_log() -> SceneLog:
    """Ego standing at the origin facing +x; a car turning right in frames 20-35; a pedestrian walking across the
    ego's path (left to right, 12 m ahead); a car following the first car 10 m behind."""
    xy, heading = _turning_car()
    ped_xy = np.c_[np.full(F, 12.0), np.linspace(6.0, -6.0, F)]
    tracks = (
        _track("veh_turn", xy, heading),
        _track("ped_00", ped_xy, np.full(F, -np.pi / 2)),
        _track("veh_follow", np.c_[np.linspace(-2.0, 37.2, F), np.zeros(F)], np.zeros(F)),
    )
    objects = (ObjectInfo("veh_turn", "vehicle", "rigid", 1, "", {}),
               ObjectInfo("ped_00", "pedestrian", "nonrigid", 2, "", {}),
               ObjectInfo("veh_follow", "vehicle", "rigid", 3, "", {}))
    return SceneLog("hand", "synthetic", (np.arange(F) * 1e6 / FPS).astype(np.int64), np.tile(np.eye(4), (F, 1, 1)),
                    (), tracks, objects, (), {}).validate()


@pytest.mark.parametrize(("text", "clauses"), [
    ("a pedestrian crossing in front of ego while a car turns right", 2),
    ("someone crossing as a vehicle slows down", 2),
    ("a ped crossing and a car turning left", 2),
    ("a car slowing down and stopping", 1),
    ("a car following the bus", 1),
])
def test_conjunctions_split_only_between_agents(text: str, clauses: int) -> None:
    assert len(parse_description(text).clauses) == clauses


def test_clause_parts_and_relations() -> None:
    q = parse_description("a pedestrian crossing in front of ego while a car turns right")
    ped, car = q.clauses
    assert ped.parsed.categories == ("pedestrian",) and voc.CROSSING in ped.motions
    assert ped.sectors == (voc.IN_FRONT_OF_EGO,) and car.motions == (voc.TURNING_RIGHT,)
    follow = parse_description("a car following the bus").clauses[0]
    assert follow.relation == FOLLOWING and follow.related is not None and follow.related.parsed.subtype == "bus"
    blocked = parse_description("the ego lane blocked by a parked truck").clauses[0]
    assert blocked.in_ego_lane and blocked.parsed.subtype == "truck" and blocked.motions == (voc.PARKED,)
    assert parse_description("a vehicle stopped on the crosswalk").clauses[0].contexts == (voc.ON_THE_CROSSWALK,)
    assert parse_description("a person on the highway shoulder").clauses[0].unknown_places == ("highway",)
    # "us" / "our car" are the ego, not a second agent
    assert len(parse_description("a car behind our car").clauses) == 1


def test_windows() -> None:
    truth = np.zeros(20, dtype=bool)
    truth[[2, 3, 4, 6, 7, 12]] = True
    assert frame_windows(truth, min_frames=3, max_gap=1) == [(2, 7)]
    assert frame_windows(truth, min_frames=1, max_gap=0) == [(2, 4), (6, 7), (12, 12)]
    assert covered([(2, 4)], 6).tolist() == [False, False, True, True, True, False]


def test_a_turn_is_found_where_it_happens(hand_log: SceneLog) -> None:
    objects = log_frames(hand_log)
    result = search_log("hand", objects, F, "a car turning right")
    assert [h.object_ids for h in result.hits] == [("veh_turn",)]
    start, end = result.hits[0].window
    assert 14 <= start <= 22 and 33 <= end <= 41  # the turn is frames 20-35; windows are +-1 s
    assert not result.frames[:10].any() and not result.frames[-5:].any()


def test_relations_and_conjunctions_on_the_hand_log(hand_log: SceneLog) -> None:
    objects = log_frames(hand_log)
    follow = search_log("hand", objects, F, "a vehicle following another car")
    assert follow.hits and follow.hits[0].object_ids == ("veh_follow", "veh_turn")
    both = search_log("hand", objects, F, "a person crossing in front of us while a car turns right")
    assert both.hits and set(both.hits[0].object_ids) == {"ped_00", "veh_turn"}


@pytest.mark.parametrize(("text", "reason"), [
    ("a reversing bus", "nothing matches 'a reversing bus'"),
    ("a pedestrian on the highway shoulder", "the map has no highway"),
])
def test_negatives_give_no_hits_with_a_reason(hand_log: SceneLog, text: str, reason: str) -> None:
    result = search_log("hand", log_frames(hand_log), F, text)
    assert result.hits == () and reason in result.message


def test_balanced_accuracy_by_hand() -> None:
    truth = np.array([True, True, False, False, False])
    pred = np.array([True, False, False, True, False])
    assert balanced_accuracy(truth, pred) == pytest.approx((1 / 2 + 2 / 3) / 2)
    assert balanced_accuracy(np.zeros(4, bool), np.array([1, 0, 0, 0], bool)) == pytest.approx(0.75)
    assert math.isnan(balanced_accuracy(np.zeros(0, bool), np.zeros(0, bool)))
    t = [np.array([True, False]), np.array([False, False]), np.array([False, True])]
    p = [np.array([True, True]), np.array([False, False]), np.array([False, False])]
    assert timestamp_ba(t, p) == pytest.approx((1 / 2 + 3 / 4) / 2)
    assert log_ba(t, p) == pytest.approx((1 / 2 + 1) / 2)
