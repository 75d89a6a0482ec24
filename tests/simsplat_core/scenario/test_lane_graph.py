"""Lane graph on the synthetic world's map and on the real Argoverse 2 map."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import load_av2_log
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.types import MapFeature
from simsplat_core.world import WorldConfig, generate_world
from simsplat_core.world.road import arm_dir

AV2_LOG = Path("av2") / "sensor-log-7fab2350"


@pytest.fixture(scope="module")
def synthetic() -> tuple[LaneGraph, object]:
    layout = generate_world(0, WorldConfig(num_frames=4, width=32, height=24)).layout
    return LaneGraph.from_features(layout.map_features()), layout


@pytest.fixture(scope="module")
def av2(shared_data: Path) -> tuple[LaneGraph, dict[str, list[str]], list[MapFeature]]:
    log_dir = shared_data / AV2_LOG
    if not log_dir.exists():
        pytest.skip("AV2 sample absent")
    log = load_av2_log(log_dir)
    doc = json.loads(next((log_dir / "map").glob("log_map_archive*.json")).read_text())
    explicit = {
        f"lane_{k}": [f"lane_{s}" for s in (v.get("successors") or [])] for k, v in doc["lane_segments"].items()
    }
    return LaneGraph.from_features(log.map_features), explicit, list(log.map_features)


def _one_lane(lane) -> LaneGraph:
    return LaneGraph.from_features([MapFeature(lane.lane_id, "lane", np.c_[lane.points, np.zeros(len(lane.points))])])


def _assert_successors_connect(graph: LaneGraph, max_gap_m: float = 6.0) -> None:
    """Every successor starts near where its predecessor ends, or the two overlap (the successor starts on
    the predecessor, or the predecessor ends on the successor: junction connectors branching off a lane)."""
    for i, nxt in enumerate(graph.successors):
        lane = graph.lanes[i]
        end = lane.points[-1]
        for j in nxt:
            successor = graph.lanes[j]
            near = np.linalg.norm(successor.points[0] - end) <= max_gap_m
            starts_on = _one_lane(lane).nearest(successor.points[:1], max_dist_m=0.6).lane[0] >= 0
            ends_on = _one_lane(successor).nearest(end[None], max_dist_m=0.6).lane[0] >= 0
            assert near or starts_on or ends_on, (lane.lane_id, successor.lane_id)
            assert i in graph.predecessors[j]


def test_synthetic_successors_turns_and_neighbours(synthetic) -> None:
    graph, layout = synthetic
    _assert_successors_connect(graph)
    w0 = graph.index("lane_W_in_0")
    names = {graph.lanes[j].lane_id for j in graph.successors[w0]}
    assert {"lane_conn_W0_straight", "lane_conn_W0_left"} <= names
    assert [graph.lanes[j].lane_id for j in graph.successors[graph.index("lane_conn_W0_straight")]] == ["lane_E_out_0"]
    # inbound lane 0 lies next to the centre line: the left lane of right-hand traffic
    w1 = graph.index("lane_W_in_1")
    assert graph.left[w1] == w0 and graph.right[w0] == w1 and graph.left[w0] == -1
    assert graph.turn_of(graph.index("lane_conn_W0_left")) == "left"
    assert graph.turn_of(graph.index("lane_conn_W0_straight")) == "straight"


@pytest.mark.parametrize("manoeuvre, sign", [("left", 1.0), ("right", -1.0), ("straight", 0.0)])
def test_synthetic_paths_through_the_junction(synthetic, manoeuvre: str, sign: float) -> None:
    graph, layout = synthetic
    lane = 0 if manoeuvre == "left" else layout.lanes("W") - 1
    start = layout.arm_point("W", layout.stopline_s("W") + 30.0, layout.lane_offset("W", True, lane))
    heading = float(np.arctan2(*(-arm_dir("W"))[::-1]))
    lp = graph.follow(start, heading, manoeuvre, max_length_m=80.0)
    dh = np.rad2deg(lp.heading_change())
    if sign == 0.0:
        assert abs(dh) < 5.0
    else:
        assert lp.turn_taken and sign * dh > 80.0
    # distances along the path: the start is 30 m before the stop line, the path goes on past it
    assert lp.path.length - lp.start_s >= 80.0
    assert np.all(np.diff(lp.path.s) > 0)


def test_nearest_lane_of_a_lane_point_is_itself(synthetic) -> None:
    graph, _ = synthetic
    for i, ln in enumerate(graph.lanes):
        mid = np.array([np.interp(ln.length / 2, ln.s, ln.points[:, c]) for c in range(2)])
        m = graph.nearest(mid[None], ln.heading_at(ln.length / 2)[None])
        assert m.distance[0] < 1e-6 and abs(m.offset[0]) < 1e-6
        assert m.lane[0] == i or graph.nearest(mid[None]).distance[0] < 1e-6  # overlapping connectors tie
    # a point 1 m to the left of a lane: positive offset, arc length along it
    ln = graph.lanes[graph.index("lane_W_in_1")]
    h = float(ln.heading_at(10.0))
    p = np.array([np.interp(10.0, ln.s, ln.points[:, c]) for c in range(2)]) + [-np.sin(h), np.cos(h)]
    m = graph.nearest(p[None], np.array([h]))
    assert (
        m.lane[0] == graph.index("lane_W_in_1") and m.offset[0] == pytest.approx(1.0) and m.s[0] == pytest.approx(10.0)
    )


@pytest.mark.shared_data
def test_av2_inferred_successors_match_the_map(av2) -> None:
    graph, explicit, features = av2
    assert len(graph) > 100
    inferred = {(graph.lanes[i].lane_id, graph.lanes[j].lane_id) for i, s in enumerate(graph.successors) for j in s}
    ids = {ln.lane_id for ln in graph.lanes}
    listed = {(a, b) for a, succ in explicit.items() for b in succ if a in ids and b in ids}
    assert listed and len(inferred & listed) >= 0.95 * len(listed)
    assert len(inferred - listed) <= 0.05 * len(listed)
    _assert_successors_connect(graph, max_gap_m=1.5)
    given = LaneGraph.from_features(features, successors=explicit)
    assert {
        (given.lanes[i].lane_id, given.lanes[j].lane_id) for i, s in enumerate(given.successors) for j in s
    } == listed


@pytest.mark.shared_data
def test_av2_turns_paths_and_neighbours(av2) -> None:
    graph, _, _ = av2
    kinds = [graph.turn_of(i) for i in range(len(graph))]
    assert kinds.count("left") > 0 and kinds.count("right") > 0
    made = {"left": 0, "right": 0}
    for i, succ in enumerate(graph.successors):  # lanes before a branch that offers the turn
        options = {graph.turn_of(j) for j in succ}
        for manoeuvre in made:
            if len(succ) > 1 and manoeuvre in options:
                ln = graph.lanes[i]
                mid = np.array([np.interp(ln.length / 2, ln.s, ln.points[:, c]) for c in range(2)])
                lp = graph.follow(mid, float(ln.heading_at(ln.length / 2)), manoeuvre, max_length_m=60.0)
                assert lp.lanes[0] == i and lp.lanes[1] in succ
                dh = np.rad2deg(lp.heading_change(*lp.lane_span(1)))  # across the branch taken
                assert lp.turn_taken and (dh > 30.0 if manoeuvre == "left" else dh < -30.0)
                made[manoeuvre] += 1
    assert made["left"] > 0 and made["right"] > 0
    assert (graph.left >= 0).sum() > 0 and (graph.right >= 0).sum() > 0
    for side, neighbours in ((1.0, graph.left), (-1.0, graph.right)):
        for i in np.flatnonzero(neighbours >= 0):
            a, b = graph.lanes[i], graph.lanes[neighbours[i]]
            mid = np.array([[np.interp(a.length / 2, a.s, a.points[:, c]) for c in range(2)]])
            h = float(a.heading_at(a.length / 2))
            on_b = LaneGraph.from_features([MapFeature(b.lane_id, "lane", np.c_[b.points, np.zeros(len(b.points))])])
            m = on_b.nearest(mid)
            assert 2.0 <= m.distance[0] <= 5.0 and -side * m.offset[0] > 0  # the neighbour is on that side
            dh = np.rad2deg(np.abs(np.angle(np.exp(1j * (b.heading_at(m.s[0]) - h)))))
            assert dh <= 15.0  # parallel
