"""Small hand-made ``SceneLog``s for the export tests: cars on a straight two-lane road at a chosen rate."""

from __future__ import annotations

import json

import numpy as np

from simsplat_core.geometry import pose_from_yaw
from simsplat_core.types import MapFeature, ObjectInfo, SceneLog, Track


def straight_road_log(num_frames: int = 40, hz: float = 10.0, *, object_ids: tuple[str, ...] = ("car_b", "car_a"),
                      road_edges: bool = True, seq_id: str = "road-seq") -> SceneLog:
    """Ego at 8 m/s along +x; each object a car 15 m further ahead per index at 6 m/s in the same lane; lanes
    ``lane_1`` -> ``lane_2`` (successors), a left lane ``lane_3``; road edges (or a drivable area), a sidewalk,
    one stop sign and one speed bump in metadata, a green signal on ``lane_1`` at every frame."""
    t = np.arange(num_frames) / hz
    timestamps = np.round(t * 1e6).astype(np.int64)
    ego = np.stack([pose_from_yaw(8.0 * s, 0.0, 0.0, 0.0) for s in t])
    tracks, objects = [], []
    for k, oid in enumerate(object_ids):
        x = 15.0 * (k + 1) + 6.0 * t
        center = np.stack([x, np.zeros_like(x), np.full_like(x, 0.8)], 1)
        tracks.append(Track(oid, np.arange(num_frames), center, np.tile([4.5, 1.9, 1.6], (num_frames, 1)),
                            np.zeros(num_frames), np.full(num_frames, 6.0), np.ones(num_frames, bool)))
        objects.append(ObjectInfo(oid, "vehicle", "rigid", k + 1))
    xs = np.linspace(-50, 250, 31)
    line = np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)], 1)
    features = [
        MapFeature("lane_1", "lane", line[:16]),
        MapFeature("lane_2", "lane", line[15:]),
        MapFeature("lane_3", "lane", line + [0, 3.5, 0]),
        MapFeature("lane_marking_4", "lane_marking", line + [0, 1.75, 0]),
        MapFeature("crosswalk_5", "crosswalk", np.array([[100, -3, 0], [104, -3, 0], [104, 6, 0], [100, 6, 0.0]])),
        MapFeature("sidewalk_6", "sidewalk", np.array([[-50, -4, 0], [250, -4, 0], [250, -7, 0], [-50, -7, 0.0]])),
    ]
    if road_edges:
        features += [MapFeature("road_edge_7", "road_edge", line - [0, 1.75, 0]),
                     MapFeature("road_edge_8", "road_edge", (line + [0, 5.25, 0])[::-1])]
    else:  # clockwise on purpose: the export must turn it counter-clockwise
        features.append(MapFeature("drivable_area_9", "drivable_area",
                                   np.array([[-50, 5.25, 0], [250, 5.25, 0], [250, -1.75, 0], [-50, -1.75, 0.0]])))
    metadata = {
        "lane_successors": json.dumps({"lane_1": ["lane_2"]}),
        "stop_signs": json.dumps([{"id": 20, "position": [60.0, -2.5, 0.0], "lanes": ["lane_2"]}]),
        "speed_bumps": json.dumps([{"id": 21, "polygon": [[80, -2, 0], [81, -2, 0], [81, 5, 0], [80, 5, 0]]}]),
        "traffic_signals": json.dumps([[["lane_1", "LANE_STATE_GO", 70.0, 0.0, 0.0]] for _ in range(num_frames)]),
        "map_feature_attributes": json.dumps({"lane_1": {"type": "TYPE_SURFACE_STREET", "left_neighbors": ["lane_3"],
                                                         "speed_limit_mph": 30.0},
                                              "lane_3": {"type": "TYPE_NOT_A_TYPE"}}),
        "ego_size": json.dumps([4.6, 2.0, 1.5]),
    }
    return SceneLog(seq_id=seq_id, source="synthetic", timestamps_us=timestamps, ego_poses=ego,
                    tracks=tuple(tracks), objects=tuple(objects), map_features=tuple(features), metadata=metadata)
