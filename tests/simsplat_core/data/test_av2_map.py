"""AV2 map geometry helpers on hand-made shapes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError
from simsplat_core.data.av2_map import (
    archive_lane_attributes,
    crosswalk_polygon,
    lane_centerline,
    load_av2_map,
    resample_polyline,
    road_edges_from_areas,
)


def _pts(*xy: tuple[float, float]) -> np.ndarray:
    return np.array([[x, y, 0.0] for x, y in xy])


def test_resample_polyline_by_arc_length() -> None:
    out = resample_polyline(_pts((0, 0), (1, 0), (4, 0)), 5)
    np.testing.assert_allclose(out[:, 0], [0, 1, 2, 3, 4])
    np.testing.assert_allclose(resample_polyline(_pts((1, 1), (1, 1)), 3), _pts((1, 1), (1, 1), (1, 1)))


def test_lane_centerline_averages_boundaries() -> None:
    left = _pts((0, 2), (10, 2))
    right = _pts((0, -2), (5, -2), (10, -2))
    center = lane_centerline(left, right)
    assert center.shape == (3, 3)
    np.testing.assert_allclose(center, _pts((0, 0), (5, 0), (10, 0)))


@pytest.mark.parametrize("reverse", [False, True])
def test_crosswalk_polygon_does_not_self_intersect(reverse: bool) -> None:
    edge1 = _pts((0, 0), (10, 0))
    edge2 = _pts((0, 3), (10, 3))
    poly = crosswalk_polygon(edge1, edge2[::-1] if reverse else edge2)
    x, y = poly[:, 0], poly[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert area == pytest.approx(30.0)


def test_road_edges_drop_shared_and_cut_edges() -> None:
    left_square = _pts((0, 0), (10, 0), (10, 10), (0, 10))
    right_square = _pts((10, 0), (20, 0), (20, 10), (10, 10))
    edges = road_edges_from_areas([left_square, right_square])
    total = sum(np.linalg.norm(np.diff(e[:, :2], axis=0), axis=1).sum() for e in edges)
    assert total == pytest.approx(60.0)  # the shared x=10 side is not a curb
    for edge in edges:  # no kept segment runs along the shared side
        on_shared_side = np.isclose(edge[:-1, 0], 10.0) & np.isclose(edge[1:, 0], 10.0)
        assert not on_shared_side.any()
    cut = np.array([[[20.0, 0.0, 0.0], [20.0, 10.0, 0.0]]])  # a lane leaves the map at x = 20
    edges = road_edges_from_areas([left_square, right_square], cut)
    total = sum(np.linalg.norm(np.diff(e[:, :2], axis=0), axis=1).sum() for e in edges)
    assert total == pytest.approx(50.0)
    assert road_edges_from_areas([left_square])[0].shape == (5, 3)  # closed loop


def test_load_av2_map_on_a_tiny_file(tmp_path: Path) -> None:
    def pts(*xy: tuple[float, float]) -> list[dict[str, float]]:
        return [{"x": x, "y": y, "z": 1.0} for x, y in xy]

    doc = {
        "lane_segments": {
            "1": {
                "id": 1,
                "lane_type": "VEHICLE",
                "left_lane_boundary": pts((0, 2), (10, 2)),
                "right_lane_boundary": pts((0, -2), (10, -2)),
                "successors": [],
                "predecessors": [],
            },
            "2": {
                "id": 2,
                "lane_type": "BIKE",
                "left_lane_boundary": pts((0, 3), (10, 3)),
                "right_lane_boundary": pts((0, 2), (10, 2)),
                "successors": [],
                "predecessors": [],
            },
        },
        "pedestrian_crossings": {"5": {"id": 5, "edge1": pts((4, -2), (4, 2)), "edge2": pts((6, -2), (6, 2))}},
        "drivable_areas": {"9": {"id": 9, "area_boundary": pts((0, -2), (10, -2), (10, 2), (0, 2))}},
    }
    path = tmp_path / "log_map_archive.json"
    path.write_text(json.dumps(doc))
    shift = np.eye(4)
    shift[:3, 3] = [-100.0, 0.0, -1.0]
    features = {f.feature_id: f for f in load_av2_map(path, shift)}
    assert set(features) == {"lane_1", "crosswalk_5", "drivable_area_9", "road_edge_0", "road_edge_1"}
    np.testing.assert_allclose(features["lane_1"].points, [[-100, 0, 0], [-90, 0, 0]])
    # Both ends of lane 1 dangle, so the area's x = 0 and x = 10 sides are crops, not curbs.
    for name in ("road_edge_0", "road_edge_1"):
        assert np.ptp(features[name].points[:, 0]) == pytest.approx(10.0)
    doc["drivable_areas"]["9"]["area_boundary"][1]["x"] = "ten"
    path.write_text(json.dumps(doc))
    with pytest.raises(CorruptLogError, match=r"field 'drivable_areas\[9\]\.area_boundary'"):
        load_av2_map(path, shift)
    path.write_text("[]")
    with pytest.raises(CorruptLogError, match="expected a JSON object"):
        load_av2_map(path, shift)


def _lane(lane_type: str, x0: float, x1: float, y: float, **links: object) -> dict[str, object]:
    """A straight AV2 lane segment from ``x0`` to ``x1`` at ``y`` (3.5 m wide) with the given link fields."""
    def boundary(dy: float) -> list[dict[str, float]]:
        return [{"x": x0, "y": y + dy, "z": 0.0}, {"x": x1, "y": y + dy, "z": 0.0}]

    return {"lane_type": lane_type, "left_lane_boundary": boundary(1.75 if x1 > x0 else -1.75),
            "right_lane_boundary": boundary(-1.75 if x1 > x0 else 1.75), **links}


def test_archive_lane_attributes_types_entries_and_same_direction_neighbours() -> None:
    # 1 and 2 run east side by side; 3 runs west left of 1 (across a centre line); 4 is a bike lane; 5 continues 1.
    doc = {"lane_segments": {
        "1": _lane("VEHICLE", 0, 50, 0, left_neighbor_id=3, right_neighbor_id=2, predecessors=[4, 9]),
        "2": _lane("BUS", 0, 50, -3.5, left_neighbor_id=1, right_neighbor_id=None),
        "3": _lane("VEHICLE", 50, 0, 3.5, left_neighbor_id=1),
        "4": _lane("BIKE", -20, 0, 0),
        "5": _lane("VEHICLE", 50, 90, 0, predecessors=[1]),
    }}
    attrs = archive_lane_attributes(doc, "map.json")
    assert sorted(attrs) == ["lane_1", "lane_2", "lane_3", "lane_5"]  # the bike lane is no map feature
    assert {a["type"] for a in attrs.values()} == {"TYPE_SURFACE_STREET"}
    assert attrs["lane_1"] == {"type": "TYPE_SURFACE_STREET", "right_neighbors": ["lane_2"]}  # 3 opposes, 4/9 absent
    assert attrs["lane_2"]["left_neighbors"] == ["lane_1"] and "right_neighbors" not in attrs["lane_2"]
    assert "left_neighbors" not in attrs["lane_3"]
    assert attrs["lane_5"]["entry_lanes"] == ["lane_1"]


def test_archive_lane_attributes_bad_predecessors_name_the_field() -> None:
    doc = {"lane_segments": {"1": _lane("VEHICLE", 0, 50, 0, predecessors=7)}}
    with pytest.raises(CorruptLogError, match=r"lane_segments\[1\]\.predecessors"):
        archive_lane_attributes(doc, "map.json")
