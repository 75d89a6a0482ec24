"""The lane routes vehicles and the ego of the procedural world follow, as ``scenario.path.Path`` s.

Routes through the junction are built from an inbound lane, the junction connector of
``road.connector_points`` (cubic Bezier approximating a circular arc for turns) and an outbound lane.
Each route records named arc lengths in ``marks`` (``"stop"``: stop line, ``"junction_in"``/
``"junction_out"``: start/end of the connector).
"""

from __future__ import annotations

import numpy as np

from simsplat_core.scenario.path import Path
from simsplat_core.world.road import RoadLayout, arm_dir, arm_normal, connector_points, target_arm, target_lane

#: Length of straight lane kept before the stop line and after the junction exit when building routes.
ROUTE_REACH = 150.0


def route(layout: RoadLayout, arm: str, lane: int, turn: str) -> Path:
    """Inbound lane of ``arm`` -> connector -> outbound lane, with marks ``stop``, ``junction_in``, ``junction_out``."""
    conn = connector_points(layout, arm, lane, turn)
    out_lane = target_lane(layout, arm, lane, turn)
    if conn is None or out_lane is None:
        raise ValueError(f"lane {lane} of arm {arm} cannot turn {turn}")
    out_arm = target_arm(arm, turn)
    d0, n0 = arm_dir(arm), arm_normal(arm)
    d1, n1 = arm_dir(out_arm), arm_normal(out_arm)
    s_stop = layout.stopline_s(arm)
    start = layout.to_world(d0 * (s_stop + ROUTE_REACH) + n0 * layout.lane_offset(arm, True, lane))
    s_exit = layout.crosswalk_range(out_arm)[1]
    end = layout.to_world(d1 * (s_exit + ROUTE_REACH) + n1 * layout.lane_offset(out_arm, False, out_lane))
    pts = np.concatenate([start[None], conn, end[None]], axis=0)
    return Path.from_points(pts, {"stop": conn[0], "junction_in": conn[0], "junction_out": conn[-1]})


def lane_change_route(
    layout: RoadLayout, arm: str, lane_from: int, lane_to: int, s_start: float, change_len: float
) -> Path:
    """Straight route along the road of ``arm`` in the inbound direction, changing lanes on the way.

    The lateral offset blends from ``lane_from`` to ``lane_to`` with a smoothstep over
    ``[s_start, s_start + change_len]`` (arc length from the route start, which lies ``ROUTE_REACH``
    metres beyond the stop line). Marks: ``stop``, ``change_start``, ``change_end``.
    """
    d0, n0 = arm_dir(arm), arm_normal(arm)
    s_stop = layout.stopline_s(arm)
    total = 2 * (s_stop + ROUTE_REACH)
    s = np.arange(0.0, total + 0.25, 0.5)
    w = np.clip((s - s_start) / change_len, 0.0, 1.0)
    w = w * w * (3.0 - 2.0 * w)
    off = (1 - w) * layout.lane_offset(arm, True, lane_from) + w * layout.lane_offset(arm, True, lane_to)
    along = s_stop + ROUTE_REACH - s  # along-arm coordinate decreases while driving inbound
    pts = layout.to_world(d0 * along[:, None] + n0 * off[:, None])
    stop_pt = layout.to_world(d0 * s_stop + n0 * off[np.argmin(np.abs(along - s_stop))])
    path = Path.from_points(pts, {"stop": stop_pt})
    path.marks["change_start"] = path.project(pts[np.argmin(np.abs(s - s_start))])
    path.marks["change_end"] = path.project(pts[np.argmin(np.abs(s - s_start - change_len))])
    return path


def polyline_path(points: np.ndarray) -> Path:
    """A path through explicit world points (pedestrian walks)."""
    return Path.from_points(np.asarray(points, dtype=np.float64))
