"""Search ground truth on hand-made agents: phases, places, sectors, relations, counts, the ego's route."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from simsplat_core.eval.search.truth import AgentSpec, WorldAgents, _route_coordinates, agent_truth, query_truth
from simsplat_core.types import SceneLog

FPS = 10.0


def _world(agents: list[dict[str, Any]], frames: int) -> WorldAgents:
    """Agents as ``dict(category=, attrs=, xy=[F, 2], heading=[F], speed=[F], ...)``; the ego stands at the origin
    facing +x (the ego frame is the world frame); every place flag defaults to off, ``on_road`` to on."""
    def stack(key: str, default: Any) -> np.ndarray:
        return np.stack([np.broadcast_to(np.asarray(a.get(key, default)), (frames,) + np.shape(default)[1:])
                         for a in agents])

    xy = np.stack([np.broadcast_to(np.asarray(a.get("xy", (0.0, 0.0)), float), (frames, 2)) for a in agents])
    return WorldAgents(
        object_ids=tuple(f"a{k}" for k in range(len(agents))), attrs=tuple(a.get("attrs", {}) for a in agents),
        categories=tuple(a.get("category", "vehicle") for a in agents), xy=xy, xy_ego=xy.copy(),
        heading=stack("heading", np.zeros(frames)), speed=stack("speed", np.zeros(frames)),
        in_junction=stack("in_junction", np.zeros(frames, bool)),
        in_crosswalk=stack("in_crosswalk", np.zeros(frames, bool)), on_road=stack("on_road", np.ones(frames, bool)),
        fps=FPS, route_lateral=stack("route_lateral", np.full(frames, np.nan)),
        route_along=stack("route_along", np.full(frames, np.nan)))


def test_attribute_filters_select_agents() -> None:
    w = _world([{"attrs": {"subtype": "SUV", "color": "red", "behavior": "parked"}},
                {"attrs": {"subtype": "sedan", "color": "red", "behavior": "straight"}},
                {"category": "pedestrian", "attrs": {"subtype": "pedestrian", "behavior": "walking"}}], 3)
    rows = lambda spec: agent_truth(w, spec).all(axis=1).tolist()  # noqa: E731
    assert rows(AgentSpec()) == [True, True, False]  # any vehicle
    assert rows(AgentSpec(subtypes=("SUV",))) == [True, False, False]
    assert rows(AgentSpec(colors=("red",), behaviors=("straight",))) == [False, True, False]
    assert rows(AgentSpec(categories=("pedestrian",))) == [False, False, True]
    assert rows(AgentSpec(colors=("purple",))) == [False, False, False]


def test_phases_follow_the_speed_profile() -> None:
    speed = np.array([5.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0])  # brakes at 10 m/s^2, then stands
    junction = np.zeros(10, bool)
    junction[3:8] = True
    road = np.ones(10, bool)
    road[:2] = False
    w = _world([{"speed": speed, "in_junction": junction, "on_road": road}], 10)

    def frames(phase: str) -> list[int]:
        return np.flatnonzero(agent_truth(w, AgentSpec(phase=phase))[0]).tolist()

    assert frames("still") == [6, 7, 8, 9]  # below 0.2 m/s
    assert frames("move") == [0, 1, 2, 3, 4, 5]  # above 0.5 m/s
    # central differences of the speed: -0.5 m/s per frame (-5 m/s^2) from frame 1 to 6, 0 at both ends
    assert frames("decelerate") == [1, 2, 3, 4, 5, 6]
    assert frames("turn") == [3, 4, 5]  # in the junction and moving
    assert frames("cross") == [2, 3, 4, 5]  # on the road and moving
    assert frames("any") == list(range(10))
    with pytest.raises(ValueError, match="unknown phase 'hover'"):
        agent_truth(w, AgentSpec(phase="hover"))


def test_lane_change_is_a_heading_off_the_road_axes() -> None:
    heading = np.array([0.0, np.deg2rad(1.0), np.deg2rad(6.0), np.pi / 2, np.pi / 2 + np.deg2rad(6.0),
                        -np.pi + np.deg2rad(1.0), np.pi - np.deg2rad(6.0)])
    w = _world([{"heading": heading}], 7)
    assert agent_truth(w, AgentSpec(phase="lane_change"))[0].tolist() == [False, False, True, False, True, False,
                                                                          True]


def test_places_and_a_place_the_world_lacks() -> None:
    cw = np.array([True, False, False])
    junction = np.array([False, True, False])
    road = np.array([True, True, False])
    w = _world([{"in_crosswalk": cw, "in_junction": junction, "on_road": road}], 3)
    assert agent_truth(w, AgentSpec(place="crosswalk"))[0].tolist() == cw.tolist()
    assert agent_truth(w, AgentSpec(place="junction"))[0].tolist() == junction.tolist()
    assert agent_truth(w, AgentSpec(place="road"))[0].tolist() == road.tolist()
    assert agent_truth(w, AgentSpec(place="sidewalk"))[0].tolist() == (~road).tolist()
    assert not agent_truth(w, AgentSpec(place="highway")).any()


@pytest.mark.parametrize(("xy", "sector"), [((10.0, 0.0), "front"), ((10.0, 9.0), "front"), ((9.0, 10.0), "left"),
                                             ((0.0, -10.0), "right"), ((-10.0, 1.0), "behind")])
def test_sectors_are_45_degree_wedges_around_the_ego(xy: tuple[float, float], sector: str) -> None:
    w = _world([{"xy": xy}], 1)
    held = [s for s in ("front", "left", "right", "behind") if agent_truth(w, AgentSpec(sector=s))[0, 0]]
    assert held == [sector]


def _pair(lead_xy: tuple[float, float], lead_heading: float = 0.0, lead_speed: float = 8.0,
          lead_attrs: dict[str, str] | None = None) -> WorldAgents:
    """Agent 0 at the origin driving +x at 8 m/s, agent 1 (the candidate leader) as given."""
    return _world([{"xy": (0.0, 0.0), "speed": np.full(1, 8.0)},
                   {"xy": lead_xy, "heading": np.full(1, lead_heading), "speed": np.full(1, lead_speed),
                    "attrs": lead_attrs or {}}], 1)


@pytest.mark.parametrize(("lead", "follows", "followed"), [
    (dict(lead_xy=(12.0, 0.5)), True, False),  # the leader does not follow the car behind it
    (dict(lead_xy=(35.0, 0.0)), False, False),  # more than 30 m ahead
    (dict(lead_xy=(12.0, 3.0)), False, False),  # the next lane
    (dict(lead_xy=(12.0, 0.0), lead_heading=np.pi), False, False),  # oncoming
    (dict(lead_xy=(12.0, 0.0), lead_speed=0.0), False, False),  # a standing car is queued behind, not followed
    (dict(lead_xy=(-12.0, 0.0)), False, True),  # behind: it follows agent 0
])
def test_following_needs_the_other_ahead_in_the_same_lane_and_direction(lead: dict[str, Any], follows: bool,
                                                                        followed: bool) -> None:
    truth = agent_truth(_pair(**lead), AgentSpec(following=AgentSpec()))
    assert bool(truth[0, 0]) is follows and bool(truth[1, 0]) is followed


def test_following_a_named_agent() -> None:
    w = _pair((12.0, 0.0), lead_attrs={"subtype": "bus"})
    assert agent_truth(w, AgentSpec(following=AgentSpec(subtypes=("bus",))))[0, 0]
    assert not agent_truth(w, AgentSpec(following=AgentSpec(subtypes=("truck",))))[0, 0]


def test_ego_lane_and_cut_in_use_the_route_coordinates() -> None:
    along = np.array([10.0, 10.0, -5.0, 45.0])
    lateral = np.array([1.0, 2.0, 0.0, 0.0])
    w = _world([{"route_along": along, "route_lateral": lateral, "speed": np.full(4, 5.0)}], 4)
    assert agent_truth(w, AgentSpec(in_ego_lane=True))[0].tolist() == [True, False, False, False]
    # a car 15 m ahead closing in on the route sideways at 1 m per frame (10 m/s), then holding its offset
    closing = np.array([4.0, 3.0, 2.0, 1.0, 1.0, 1.0])
    w = _world([{"route_along": np.full(6, 15.0), "route_lateral": closing}], 6)
    assert agent_truth(w, AgentSpec(cut_in=True))[0].tolist() == [True, True, True, True, False, False]


def test_query_truth_needs_every_spec_in_the_same_frame() -> None:
    w = _world([{"speed": np.array([5.0, 5.0, 0.0, 0.0])},
                {"category": "pedestrian", "speed": np.array([0.0, 1.0, 1.0, 0.0])}], 4)
    car_moves = AgentSpec(phase="move")
    ped_moves = AgentSpec(categories=("pedestrian",), phase="move")
    assert query_truth(w, (car_moves,)).tolist() == [True, True, False, False]
    assert query_truth(w, (car_moves, ped_moves)).tolist() == [False, True, False, False]


def test_count_and_together() -> None:
    walking = np.array([1.0, 1.0, 0.0])
    # two pedestrians walking side by side (2 m apart), a third walking alone 20 m away in frame 0 only
    w = _world([{"category": "pedestrian", "xy": (0.0, 0.0), "speed": walking},
                {"category": "pedestrian", "xy": (0.0, 2.0), "speed": np.array([1.0, 0.0, 0.0])},
                {"category": "pedestrian", "xy": (20.0, 0.0), "speed": np.array([1.0, 1.0, 1.0])}], 3)
    def walkers(count: int, together: bool = False) -> AgentSpec:
        return AgentSpec(categories=("pedestrian",), phase="move", count=count, together=together)

    assert query_truth(w, (walkers(2),)).tolist() == [True, True, False]  # any two at once
    assert query_truth(w, (walkers(3),)).tolist() == [True, False, False]
    # together: only the side-by-side pair counts, and only while both walk
    assert query_truth(w, (walkers(2, together=True),)).tolist() == [True, False, False]


def test_route_coordinates_bend_with_the_ego_route() -> None:
    """The ego drives 10 m east, turns left on a 10 m radius, then drives north, 1 m per frame; the ego lane
    bends with the route instead of running straight on from the ego."""
    ang = np.arange(0.0, np.pi / 2, 0.1)
    east = np.stack([np.arange(0.0, 10.0), np.zeros(10)], 1)
    bend = np.stack([10.0 + 10.0 * np.sin(ang), 10.0 - 10.0 * np.cos(ang)], 1)
    north = np.stack([np.full(20, 20.0), 10.0 + np.arange(20.0)], 1)
    ego_xy = np.concatenate([east, bend, north])
    heading = np.unwrap(np.arctan2(*np.gradient(ego_xy, axis=0)[:, ::-1].T))
    on_route_later = ego_xy[30] + [0.5, 0.0]  # 0.5 m to the right of where the ego will be at frame 30
    beside_now = ego_xy[0] + [5.0, 2.5]  # 5 m ahead of the ego, 2.5 m to its left
    behind = ego_xy[0] + [-4.0, 0.0]
    agents = np.stack([np.broadcast_to(p, (len(ego_xy), 2)) for p in (on_route_later, beside_now, behind)])
    along, lateral = _route_coordinates(agents, ego_xy, heading)
    travelled = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(ego_xy, axis=0), axis=1))]
    assert along[0, 0] == pytest.approx(travelled[30], abs=0.3)
    assert lateral[0, 0] == pytest.approx(-0.5, abs=0.1)  # to the right of the route: negative
    assert along[1, 0] == pytest.approx(5.0, abs=0.1) and lateral[1, 0] == pytest.approx(2.5, abs=0.1)
    assert along[2, 0] == pytest.approx(-4.0, abs=1e-9)  # behind the ego: negative
    # as the ego drives past the agent beside its start, the agent falls behind
    assert along[1, 10] < 0


def test_world_agents_from_a_synthetic_log(synthetic_log: SceneLog) -> None:
    w = WorldAgents.from_log(synthetic_log)
    movable = [o for o in synthetic_log.objects if o.category in ("vehicle", "pedestrian", "cyclist")]
    assert w.object_ids == tuple(o.object_id for o in movable) + ("ego",)
    assert w.categories[-1] == "ego" and "sign" not in w.categories
    turn = synthetic_log.metadata["ego_route"].split(" ")[-1]
    assert w.attrs[-1]["behavior"] == {"left": "turn_left", "right": "turn_right"}.get(turn, "straight")
    F = synthetic_log.num_frames
    assert w.xy.shape == (len(movable) + 1, F, 2) and w.speed.shape == w.on_road.shape == (len(movable) + 1, F)
    np.testing.assert_allclose(w.xy[-1], synthetic_log.ego_poses[:, :2, 3])
    np.testing.assert_allclose(w.xy_ego[-1], 0.0, atol=1e-9)  # the ego sits at its own origin
    assert w.fps == pytest.approx(1e6 / np.diff(synthetic_log.timestamps_us).mean())
