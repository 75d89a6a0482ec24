"""The rule-based motion/location labeller on hand-built trajectories, and against the synthetic world."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.eval.motion import labeller_agreement
from simsplat_core.language.motion_labels import label_log
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.types import MapFeature

from .scenes import FRAMES, arc, lane, lane_change, polygon, scene, straight, times


def _motion(objects, **kw) -> dict[str, str]:
    return {oid: lb.motion for oid, lb in label_log(scene(objects, **kw)).items()}


def test_vehicle_manoeuvres_without_a_map() -> None:
    decel = np.maximum(8.0 - 3.0 * times(), 0.0)
    labels = _motion(
        {
            "straight": ("vehicle", *straight((10.0, 0.0), 0.0, 8.0)),
            "left": ("vehicle", *arc(12.0, 90.0)),
            "right": ("vehicle", *arc(12.0, -90.0)),
            "lc_left": ("vehicle", *lane_change(+1.0)),
            "lc_right": ("vehicle", *lane_change(-1.0)),
            "stop": ("vehicle", *straight((10.0, 3.5), 0.0, decel)),
            "slow": ("vehicle", *straight((10.0, -3.5), 0.0, np.maximum(9.0 - 1.5 * times(), 3.0))),
            "reverse": ("vehicle", straight((20.0, 7.0), np.pi, 2.0)[0], np.zeros(FRAMES)),
            "static": ("vehicle", *straight((30.0, 0.0), 0.0, 0.0)),
        }
    )
    assert labels == {
        "straight": voc.GOING_STRAIGHT,
        "left": voc.TURNING_LEFT,
        "right": voc.TURNING_RIGHT,
        "lc_left": voc.CHANGING_LANE_LEFT,
        "lc_right": voc.CHANGING_LANE_RIGHT,
        "stop": voc.STOPPING,
        "slow": voc.SLOWING_DOWN,
        "reverse": voc.REVERSING,
        "static": voc.STOPPED,
    }


def test_lane_change_is_measured_against_lanes_not_the_initial_heading() -> None:
    # a long gentle left curve (radius 250 m): 1.9 m off the initial heading line after 4 s
    radius, speed = 250.0, 8.0
    ang = speed * times() / radius
    curve_xy = np.stack([radius * np.sin(ang), radius * (1.0 - np.cos(ang))], axis=1)
    lane_ang = np.linspace(-0.2, 0.5, 60)
    curved_lane = MapFeature(
        "curve", "lane", np.stack([radius * np.sin(lane_ang), radius * (1.0 - np.cos(lane_ang)), 0 * lane_ang], axis=1)
    )
    follow = ("vehicle", curve_xy, ang)
    assert _motion({"follow": follow}) == {"follow": voc.CHANGING_LANE_LEFT}  # no map: initial-heading fallback
    assert _motion({"follow": follow}, map_features=(curved_lane,)) == {"follow": voc.GOING_STRAIGHT}
    lanes = (lane("l0", 0.0), lane("l1", 3.5))
    labels = _motion(
        {"lc": ("vehicle", *lane_change(+1.0)), "drift": ("vehicle", *straight((5.0, 1.0), 0.0, 8.0))},
        map_features=lanes,
    )
    assert labels == {"lc": voc.CHANGING_LANE_LEFT, "drift": voc.GOING_STRAIGHT}


def test_parked_versus_stopped_uses_the_lanes() -> None:
    feats = (lane("l0", 0.0), polygon("drivable_area", "road", -50.0, 150.0, -6.0, 6.0))
    labels = _motion(
        {
            "in_lane": ("vehicle", *straight((15.0, 0.2), 0.0, 0.0)),
            "kerb": ("vehicle", *straight((15.0, 4.5), 0.0, 0.0)),
        },
        map_features=feats,
    )
    assert labels == {"in_lane": voc.STOPPED, "kerb": voc.PARKED}


@pytest.mark.parametrize("ego_yaw", [0.0, np.pi / 2, -2.5])
def test_pedestrian_crossing_direction_is_relative_to_the_ego(ego_yaw: float) -> None:
    # in the ego frame (x forward, y left): walking towards -y crosses from left to right
    objects = {
        "l2r": ("pedestrian", *straight((15.0, 6.0), -np.pi / 2, 1.4)),
        "r2l": ("pedestrian", *straight((18.0, -6.0), np.pi / 2, 1.4)),
        "stand": ("pedestrian", *straight((12.0, 8.0), 0.3, 0.0)),
        "along": ("pedestrian", *straight((5.0, 9.0), 0.0, 1.3)),
    }
    labels = _motion(objects, ego_yaw=ego_yaw)
    assert labels == {
        "l2r": voc.CROSSING_LEFT_TO_RIGHT,
        "r2l": voc.CROSSING_RIGHT_TO_LEFT,
        "stand": voc.STANDING,
        "along": voc.WALKING_ALONG,
    }


def test_pedestrian_crossing_needs_the_road_when_the_map_has_one() -> None:
    feats = (
        polygon("drivable_area", "road", -50.0, 150.0, -5.0, 5.0),
        polygon("sidewalk", "walk_n", -50.0, 150.0, 5.0, 9.0),
        polygon("drivable_area", "side_street", 30.0, 40.0, -60.0, 60.0),
    )
    objects = {
        "cross": ("pedestrian", *straight((15.0, 6.0), -np.pi / 2, 1.4)),
        # lateral to the ego but on a sidewalk strip beside a side street: not crossing
        "side": ("pedestrian", *straight((27.0, 10.0), np.pi / 2, 1.4)),
        # along the ego's road but inside the side street's roadway: crossing it, not lateral
        "side_cross": ("pedestrian", *straight((29.0, 7.0), 0.0, 1.4)),
    }
    labels = _motion(objects, map_features=feats)
    assert labels == {"cross": voc.CROSSING_LEFT_TO_RIGHT, "side": voc.WALKING_ALONG, "side_cross": voc.CROSSING}


def test_location_sectors_and_oncoming() -> None:
    log = scene(
        {
            "front": ("vehicle", *straight((20.0, 1.0), 0.0, 0.0)),
            "behind": ("vehicle", *straight((-15.0, 0.0), 0.0, 0.0)),
            "left": ("pedestrian", *straight((2.0, 8.0), 0.0, 0.0)),
            "right": ("pedestrian", *straight((1.0, -8.0), 0.0, 0.0)),
            "oncoming": ("vehicle", *straight((40.0, 3.5), np.pi, 6.0)),
        }
    )
    labels = label_log(log)
    assert {k: v.sector for k, v in labels.items()} == {
        "front": voc.IN_FRONT_OF_EGO,
        "behind": voc.BEHIND_EGO,
        "left": voc.LEFT_OF_EGO,
        "right": voc.RIGHT_OF_EGO,
        "oncoming": voc.IN_FRONT_OF_EGO,
    }
    assert labels["oncoming"].context == voc.IN_THE_ONCOMING_LANE
    assert labels["front"].context == voc.ON_THE_ROAD


def test_location_contexts_from_the_map() -> None:
    crosswalks = tuple(
        polygon("crosswalk", f"cw{k}", x0, x0 + 3.0, -7.0, 7.0) for k, x0 in enumerate((20.0, 40.0))
    )
    feats = (
        polygon("drivable_area", "road", -50.0, 150.0, -7.0, 7.0),
        polygon("sidewalk", "walk", -50.0, 150.0, 7.0, 11.0),
        lane("l0", 1.75),
        lane("l1", -1.75, reverse=True),
        *crosswalks,
    )
    log = scene(
        {
            "junction": ("vehicle", *straight((31.0, 1.75), 0.0, 0.0)),
            "zebra": ("pedestrian", *straight((21.5, 3.0), 0.0, 0.0)),
            "walk": ("pedestrian", *straight((60.0, 9.0), 0.0, 0.0)),
            "kerb": ("vehicle", *straight((70.0, 5.5), 0.0, 0.0)),
            "oncoming": ("vehicle", *straight((90.0, -1.75), np.pi, 0.0)),
            "lane": ("vehicle", *straight((80.0, 1.75), 0.0, 0.0)),
        },
        map_features=feats,
    )
    contexts = {k: v.context for k, v in label_log(log).items()}
    assert contexts == {
        "junction": voc.AT_THE_INTERSECTION,
        "zebra": voc.ON_THE_CROSSWALK,
        "walk": voc.ON_THE_SIDEWALK,
        "kerb": voc.BY_THE_CURB,
        "oncoming": voc.IN_THE_ONCOMING_LANE,
        "lane": voc.ON_THE_ROAD,
    }


def test_static_objects_are_not_labelled() -> None:
    log = scene(
        {"cone": ("static", *straight((10.0, 2.0), 0.0, 0.0)), "car": ("vehicle", *straight((10.0, -2.0), 0.0, 0.0))}
    )
    assert set(label_log(log)) == {"car"}


def test_labeller_agrees_with_the_synthetic_world(held_out_log) -> None:
    report = labeller_agreement([held_out_log])
    assert report.objects >= 10
    assert report.motion >= 0.95, report.disagreements
    assert report.sector == 1.0, report.disagreements
    assert report.context >= 0.9, report.disagreements
