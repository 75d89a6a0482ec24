"""Captions are true of the trajectories: recomputed by the description functions, and checked
against independent geometric facts (heading change, speed, ego-frame position, map polygons)."""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest

from simsplat_core.types import Track
from simsplat_core.world import describe_track, layout_from_log, reference_frame
from simsplat_core.world.captions import describe_appearance, describe_motion

from .test_map import point_in_polygon


def _ego_xy(log, xy, frame):
    pose = log.ego_poses[frame]
    rel = np.asarray(xy) - pose[:2, 3]
    return pose[:2, :2].T @ rel


def _polygons(log, kind):
    return [f.points[:, :2] for f in log.map_features if f.kind == kind]


def _inside_any(points, polygons):
    return np.any([point_in_polygon(np.atleast_2d(points), p) for p in polygons], axis=0)


def test_stored_captions_match_recomputed_descriptions(full_logs):
    for log in full_logs.values():
        layout = layout_from_log(log)
        for obj in log.objects:
            tr = log.track(obj.object_id)
            desc = describe_track(tr, obj.category, layout, log.ego_poses)
            a = obj.attributes
            assert a["caption_motion"] == desc.motion
            assert a["caption_location"] == desc.location
            assert int(a["caption_frame"]) == desc.ref_frame == reference_frame(tr)
            assert a["caption_appearance"] == describe_appearance(obj.category, a)
            for part in (a["caption_appearance"], desc.motion if obj.category not in ("static", "sign") else ""):
                assert part in obj.caption


def test_motion_captions_match_geometry(full_logs):
    seen = set()
    for log in full_logs.values():
        drivable = _polygons(log, "drivable_area")
        sidewalks = _polygons(log, "sidewalk")
        for obj in log.objects:
            tr = log.track(obj.object_id)
            motion = obj.attributes["caption_motion"]
            seen.add(motion)
            dh = np.rad2deg(np.unwrap(tr.heading)[-1] - tr.heading[0])
            disp = np.linalg.norm(tr.center[-1, :2] - tr.center[0, :2])
            still = tr.speed.max() < 0.3 and disp < 0.5
            if motion == "turning left":
                assert dh > 60
            elif motion == "turning right":
                assert dh < -60
            elif motion == "going straight":
                assert abs(dh) < 25 and tr.speed.min() > 0.3
            elif motion.startswith("changing lanes"):
                h0 = tr.heading[0]
                lat = (tr.center[-1, :2] - tr.center[0, :2]) @ np.array([-np.sin(h0), np.cos(h0)])
                assert abs(dh) < 25 and abs(lat) > 1.5
                assert (lat > 0) == motion.endswith("left")
            elif motion in ("parked", "stopped", "standing", "stationary"):
                assert still
            elif motion == "coming to a stop":
                assert tr.speed[0] > 2.0 and tr.speed[-1] < 0.3
            elif motion == "slowing down":
                assert tr.speed[-1] < 0.65 * tr.speed[0]
            elif motion.startswith("crossing the street"):
                assert not still
                assert _inside_any(tr.center[:, :2], drivable).any()  # the path is on the road
                if motion.endswith("left to right") or motion.endswith("right to left"):
                    ref = int(obj.attributes["caption_frame"])
                    moving = np.nonzero(tr.speed > 0.3)[0]
                    y0 = _ego_xy(log, tr.center[moving[0], :2], ref)[1]
                    y1 = _ego_xy(log, tr.center[moving[-1], :2], ref)[1]
                    assert (y1 < y0) == motion.endswith("left to right")
            elif motion == "walking along the sidewalk":
                assert not still
                assert _inside_any(tr.center[:, :2], sidewalks).mean() >= 0.5
            if obj.category == "pedestrian":
                assert motion in ("standing", "walking along the sidewalk", "walking") or motion.startswith("crossing")
    # the scenes exercise the main behaviours
    assert {"going straight", "standing", "walking along the sidewalk"} <= seen
    assert any(m.startswith("turning") for m in seen)
    assert any(m.startswith("crossing the street") for m in seen)
    assert seen & {"parked", "stopped", "coming to a stop", "slowing down"}


def test_location_captions_match_geometry(full_logs):
    for log in full_logs.values():
        layout = layout_from_log(log)
        sidewalks = _polygons(log, "sidewalk")
        crosswalks = _polygons(log, "crosswalk")
        for obj in log.objects:
            tr = log.track(obj.object_id)
            ref = int(obj.attributes["caption_frame"])
            row = tr.index_of(ref)
            xy = tr.center[row, :2]
            x, y = _ego_xy(log, xy, ref)
            loc = obj.attributes["caption_location"]
            if loc.startswith("in front of ego"):
                assert x > 0 and abs(y) <= x + 1e-9
            elif loc.startswith("behind ego"):
                assert x < 0
            elif loc.startswith("on the left of ego"):
                assert y > 0
            elif loc.startswith("on the right of ego"):
                assert y < 0
            else:
                pytest.fail(f"{obj.object_id}: location without ego relation: {loc!r}")
            if loc.endswith("on the sidewalk"):
                assert _inside_any(xy, sidewalks)[0]
            if loc.endswith("on the crosswalk"):
                assert _inside_any(xy, crosswalks)[0]
            if loc.endswith("at the intersection"):
                u, v = np.abs(xy - np.asarray(layout.center))
                assert (
                    u <= layout.stopline_s("E") + layout.corner_radius
                    and v <= layout.stopline_s("N") + layout.corner_radius
                )
            if loc.endswith("in the oncoming lane"):
                ego_yaw = np.arctan2(log.ego_poses[ref, 1, 0], log.ego_poses[ref, 0, 0])
                assert np.cos(tr.heading[row] - ego_yaw) < np.cos(np.deg2rad(135.0)) + 1e-9
            if loc.endswith("by the curb"):
                lateral = abs(xy[1] - layout.center[1])
                assert layout.lanes_h * layout.lane_w_h <= lateral <= layout.hw_h


def test_lookalikes_exist(full_logs):
    for log in full_logs.values():
        groups = defaultdict(set)
        for obj in log.objects:
            key = (obj.category, obj.attributes["subtype"], obj.attributes["caption_appearance"])
            groups[key].add(obj.attributes["caption_motion"])
        ambiguous = {k for k, motions in groups.items() if len(motions) > 1}
        assert any(k[0] == "vehicle" for k in ambiguous), "no pair of identical-looking vehicles with different motion"
        assert any(k[0] == "pedestrian" for k in ambiguous), (
            "no pair of identically dressed pedestrians with different motion"
        )
        # the designated vehicle pair: same subtype and colour, one turning and one not
        pair = [o for o in log.objects if o.attributes.get("lookalike_group") == "vehicle_pair"]
        assert len(pair) == 2
        assert pair[0].attributes["color"] == pair[1].attributes["color"]
        assert pair[0].attributes["subtype"] == pair[1].attributes["subtype"]
        assert sum(o.attributes["caption_motion"].startswith("turning") for o in pair) == 1


def _track(xy, heading, speed) -> Track:
    n = len(xy)
    center = np.concatenate([np.asarray(xy, float), np.full((n, 1), 0.75)], axis=1)
    return Track(
        "t",
        np.arange(n),
        center,
        np.tile([4.5, 1.8, 1.5], (n, 1)),
        np.asarray(heading, float),
        np.asarray(speed, float),
        np.ones(n, bool),
    )


def test_describe_motion_on_synthetic_tracks(full_logs):
    log = full_logs[7]
    layout = layout_from_log(log)
    poses = np.repeat(np.eye(4)[None], 20, axis=0)
    t = np.linspace(0.0, np.pi / 2, 20)
    left_turn = _track(np.stack([10 * np.sin(t), 10 - 10 * np.cos(t)], 1), t, np.full(20, 5.0))
    assert describe_motion(left_turn, "vehicle", layout, poses) == "turning left"
    right_turn = _track(np.stack([10 * np.sin(t), -10 + 10 * np.cos(t)], 1), -t, np.full(20, 5.0))
    assert describe_motion(right_turn, "vehicle", layout, poses) == "turning right"
    x = np.linspace(0, 20, 20)
    assert (
        describe_motion(_track(np.stack([x, 0 * x], 1), 0 * x, np.full(20, 8.0)), "vehicle", layout, poses)
        == "going straight"
    )
    lane_change = _track(np.stack([x, np.linspace(0, 3.5, 20)], 1), 0 * x, np.full(20, 8.0))
    assert describe_motion(lane_change, "vehicle", layout, poses) == "changing lanes to the left"
    braking = _track(np.stack([x, 0 * x], 1), 0 * x, np.concatenate([np.linspace(8.0, 0.0, 15), np.zeros(5)]))
    assert describe_motion(braking, "vehicle", layout, poses) == "coming to a stop"
    still = _track(np.zeros((20, 2)) + layout.center, np.zeros(20), np.zeros(20))
    assert describe_motion(still, "vehicle", layout, poses) == "stopped"
    assert describe_motion(still, "pedestrian", layout, poses) == "standing"
