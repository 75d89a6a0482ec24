"""Map features: valid, all required kinds, a four-way intersection around the ego's route."""

from __future__ import annotations

import numpy as np

from simsplat_core.types import MAP_KINDS
from simsplat_core.world import layout_from_log


def point_in_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd ray casting; ``points [N, 2]``, ``polygon [P, 2]`` (implicitly closed)."""
    x, y = points[:, 0][:, None], points[:, 1][:, None]
    a, b = polygon, np.roll(polygon, -1, axis=0)
    crosses = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_int = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (np.sum(crosses & (x < x_int), axis=1) % 2) == 1


def test_map_features_valid(full_logs):
    for log in full_logs.values():
        feats = log.map_features
        ids = [f.feature_id for f in feats]
        assert len(set(ids)) == len(ids)
        kinds = {f.kind for f in feats}
        assert kinds == set(MAP_KINDS)
        for f in feats:
            f.validate()
            assert np.all(np.isfinite(f.points))
            assert np.all(f.points[:, 2] == 0.0)
            assert len(f.points) >= (3 if f.kind in ("crosswalk", "drivable_area", "sidewalk") else 2)


def test_four_way_intersection(full_logs):
    for log in full_logs.values():
        feats = log.map_features
        by_kind = {k: [f for f in feats if f.kind == k] for k in MAP_KINDS}
        assert len(by_kind["crosswalk"]) == 4
        assert len(by_kind["road_edge"]) == 4
        assert len(by_kind["sidewalk"]) == 4
        assert len(by_kind["drivable_area"]) == 1
        drivable = by_kind["drivable_area"][0].points[:, :2]
        layout = layout_from_log(log)
        center = np.asarray(layout.center)
        # the junction centre and the four arms (50 m out) are drivable; sidewalks are not
        probes = center + np.array([[0, 0], [50, 0], [-50, 0], [0, 50], [0, -50]], dtype=float)
        assert point_in_polygon(probes, drivable).all()
        # a point in the middle of each of the four sidewalks lies in exactly one sidewalk polygon, off the road
        for su in (-1.0, 1.0):
            for sv in (-1.0, 1.0):
                probe = center + np.array([su * 30.0, sv * (layout.hw_h + layout.sidewalk_w / 2)])
                hits = [point_in_polygon(probe[None], sw.points[:, :2])[0] for sw in by_kind["sidewalk"]]
                assert sum(hits) == 1
                assert not point_in_polygon(probe[None], drivable)[0]
        # connector lanes exist for all three manoeuvres, and multi-lane roads
        conn = [f.feature_id for f in by_kind["lane"] if f.feature_id.startswith("lane_conn_")]
        for turn in ("straight", "left", "right"):
            assert any(c.endswith(turn) for c in conn)
        assert layout.lanes_h >= 2
        # all lane centre lines stay on the drivable area (segment midpoints: end points lie on its border)
        for lane in by_kind["lane"]:
            mids = 0.5 * (lane.points[1:, :2] + lane.points[:-1, :2])
            assert point_in_polygon(mids, drivable).all(), lane.feature_id


def test_ego_drives_on_lanes_through_intersection(full_logs):
    for log in full_logs.values():
        layout = layout_from_log(log)
        ego_xy = log.ego_poses[:, :2, 3]
        drivable = next(f for f in log.map_features if f.kind == "drivable_area").points[:, :2]
        assert point_in_polygon(ego_xy, drivable).all()
        # the ego reaches the junction during the sequence
        assert np.any(layout.in_junction(ego_xy))
        # the ego starts on a straight lane centre line through the origin, heading +x
        lanes = [f.points[:, :2] for f in log.map_features if f.kind == "lane"]
        assert any(
            np.allclose(pts[:, 1], 0.0, atol=1e-6)
            and pts[:, 0].min() <= 0.0 <= pts[:, 0].max()
            and pts[-1, 0] > pts[0, 0]
            for pts in lanes
        )
