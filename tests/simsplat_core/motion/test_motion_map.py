"""The map a predictor drives on, from map features of any source."""

from __future__ import annotations

import json

import numpy as np
import pytest

from simsplat_core.data.common import LANE_SUCCESSORS_KEY
from simsplat_core.motion.motion_map import motion_map_from_features, motion_map_of
from simsplat_core.types import MapFeature, SceneLog
from tests.simsplat_core.language.scenes import lane, polygon


def _log(features: list[MapFeature], metadata: dict[str, str] | None = None) -> SceneLog:
    return SceneLog("maplog", "synthetic", np.arange(3, dtype=np.int64) * 100_000, np.tile(np.eye(4), (3, 1, 1)),
                    map_features=tuple(features), metadata=metadata or {})


def _edge() -> MapFeature:
    return MapFeature("edge", "road_edge", np.array([[0.0, -2.0, 0.0], [50.0, -2.0, 0.0], [80.0, -10.0, 0.0]]))


def test_lanes_context_and_road_edges_in_polyline_order() -> None:
    mp = motion_map_from_features([lane("a", 0.0, 0.0, 100.0), lane("b", 3.5, 0.0, 100.0),
                                   polygon("drivable_area", "road", 0.0, 100.0, -2.0, 5.0), _edge()])
    assert [ln.lane_id for ln in mp.lanes.lanes] == ["a", "b"]
    assert mp.lanes.left[0] == 1 and mp.lanes.right[1] == 0  # b is a's left neighbour
    assert mp.road_edges.shape == (2, 2, 2)
    np.testing.assert_allclose(mp.road_edges, [[[0.0, -2.0], [50.0, -2.0]], [[50.0, -2.0], [80.0, -10.0]]])


def test_a_map_without_lanes_gives_an_empty_graph() -> None:
    mp = motion_map_from_features([polygon("crosswalk", "cw", 0.0, 4.0, -2.0, 2.0)])
    assert len(mp.lanes) == 0 and mp.road_edges.shape == (0, 2, 2)
    assert len(motion_map_from_features([]).lanes) == 0


def test_successors_are_inferred_from_geometry_without_stored_ones() -> None:
    mp = motion_map_of(_log([lane("a", 0.0, 0.0, 50.0), lane("b", 0.0, 50.0, 100.0), lane("far", 40.0, 200.0, 250.0)]))
    a, b, far = (mp.lanes.index(i) for i in ("a", "b", "far"))
    assert mp.lanes.successors[a] == (b,) and mp.lanes.successors[far] == ()


def test_stored_successors_win_over_geometry() -> None:
    stored = {LANE_SUCCESSORS_KEY: json.dumps({"a": ["far"], "far": ["missing"]})}
    mp = motion_map_of(_log([lane("a", 0.0, 0.0, 50.0), lane("b", 0.0, 50.0, 100.0), lane("far", 40.0, 200.0, 250.0)],
                            stored))
    a, far = mp.lanes.index("a"), mp.lanes.index("far")
    assert mp.lanes.successors[a] == (far,)  # the touching lane b is not one: the loader said so
    assert mp.lanes.successors[far] == ()  # ids missing from the map are dropped


def test_stored_successors_that_are_not_an_object_are_an_error_naming_the_log() -> None:
    with pytest.raises(ValueError, match=f"maplog: metadata '{LANE_SUCCESSORS_KEY}' is not a JSON object"):
        motion_map_of(_log([lane("a", 0.0)], {LANE_SUCCESSORS_KEY: json.dumps(["a", "b"])}))
