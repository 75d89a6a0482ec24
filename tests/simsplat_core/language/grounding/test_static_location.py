"""Static objects' ego-relative sectors: the shares from geometry, and grounding "the stop sign ahead of us"
between two stop signs that tie on appearance."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.grounding.static_location import SIGHT_M, sector_shares, with_static_locations
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from tests.simsplat_core.language.language_scene_factory import ObjectSpec, hand_built_scene, vehicle_caption

T = 20


def _states(objects: dict[str, tuple[float, float]]) -> AgentStates:
    """The ego driving along +x at 5 m/s from the origin, and static objects at the given points."""
    ids = (EGO_ID, *objects)
    a = len(ids)
    xy = np.zeros((a, T, 2))
    xy[0, :, 0] = 0.5 * np.arange(T)
    for k, point in enumerate(objects.values(), start=1):
        xy[k] = point
    return AgentStates(object_ids=ids, categories=("vehicle",) + ("sign",) * (a - 1), sources=("log",) * a,
                       node_ids=np.arange(a) - 1, frame_idx=np.arange(T), times=np.arange(T) / 10.0, xy=xy,
                       z=np.ones((a, T)), heading=np.zeros((a, T)), speed=np.zeros((a, T)),
                       size=np.ones((a, 3)), valid=np.ones((a, T), bool))


def test_sector_shares_follow_the_ego_driving_past():
    ego = np.stack([np.linspace(0, 40, 41), np.zeros(41)], axis=1)
    shares = sector_shares(np.tile([[20.0, -3.0]], (41, 1)), ego, np.zeros(41))
    assert set(shares) == {voc.IN_FRONT_OF_EGO, voc.RIGHT_OF_EGO, voc.BEHIND_EGO}
    assert shares[voc.IN_FRONT_OF_EGO] > shares[voc.RIGHT_OF_EGO]
    assert sum(shares.values()) == pytest.approx(1.0)
    turned = sector_shares(np.array([[0.0, 10.0]]), np.zeros((1, 2)), np.array([np.pi / 2]))  # ego facing +y
    assert turned == {voc.IN_FRONT_OF_EGO: 1.0}


def test_objects_beyond_sight_count_only_when_never_in_sight():
    far = sector_shares(np.array([[SIGHT_M + 50, 0.0], [-(SIGHT_M + 50), 0.0]]), np.zeros((2, 2)), np.zeros(2))
    assert far == {voc.IN_FRONT_OF_EGO: 0.5, voc.BEHIND_EGO: 0.5}


@pytest.mark.parametrize("words, expected", [("the stop sign ahead of us", "sign_ahead"),
                                             ("the stop sign on our left", "sign_left")])
def test_grounding_tells_two_stop_signs_apart_by_where_they_are(encoder, words, expected):
    caption = vehicle_caption("red", "stop sign", "sign")
    specs = [ObjectSpec(oid, "sign", caption) for oid in ("sign_left", "sign_ahead")]
    scene = hand_built_scene(specs, encoder)
    located = with_static_locations(scene, _states({"sign_left": (3.0, 15.0), "sign_ahead": (40.0, -2.0)}))
    assert all(n.static_location for n in located.nodes)
    found = QueryEngine(encoder).ground(located, words)
    assert [located.node(n).object_id for n in found.node_ids] == [expected]
