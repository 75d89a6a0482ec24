"""Motion of agents: analytic speed profiles along paths, and the behaviour recipes that build them.

A ``Motion`` is a ``Path`` plus a ``SpeedProfile`` (piecewise constant acceleration with target
speeds, never negative), so the arc length ``s(t)`` and speed ``v(t)`` are exact at any time.
Recipes turn a high-level behaviour (drive a route, stop at the stop line, slow down, change lanes,
park, cross the street, walk along the sidewalk, stand) into a ``Motion``; they take every random
choice from the caller's ``numpy.random.Generator``.

The ``behavior`` label of a motion is what the generator *intended*; captions are derived from the
sampled trajectory geometry instead (see ``captions.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.scenario.path import Path
from simsplat_core.world.paths import ROUTE_REACH, lane_change_route, polyline_path, route
from simsplat_core.world.road import RoadLayout, arm_dir, arm_normal


@dataclass(frozen=True)
class SpeedProfile:
    """Arc length ``s(t)`` from an initial state and a list of acceleration commands.

    Attributes:
        s0: arc length at ``t = 0``.
        v0: speed at ``t = 0`` (m/s, >= 0).
        changes: ``((t_start, accel, v_target), ...)`` sorted by ``t_start``: from ``t_start`` on,
            accelerate with ``accel`` until the speed reaches ``v_target``, then hold it.
    """

    s0: float
    v0: float
    changes: tuple[tuple[float, float, float], ...] = ()

    def _pieces(self, t_end: float) -> list[tuple[float, float, float, float]]:
        """Pieces ``(t0, s0, v0, a)`` of constant acceleration covering ``[0, t_end]``."""
        pieces: list[tuple[float, float, float, float]] = []
        t, s, v = 0.0, self.s0, self.v0
        cmds = [(0.0, 0.0, self.v0)] + [c for c in self.changes]
        for i, (t_cmd, acc, v_tgt) in enumerate(cmds):
            t_next = cmds[i + 1][0] if i + 1 < len(cmds) else max(t_end, t_cmd) + 1.0
            t_cmd = max(t_cmd, t)
            if t_cmd > t:  # hold the current speed until the command starts
                pieces.append((t, s, v, 0.0))
                s += v * (t_cmd - t)
                t = t_cmd
            v_tgt = max(v_tgt, 0.0)
            if acc != 0.0 and (v_tgt - v) * acc > 0:
                t_reach = min(t + (v_tgt - v) / acc, t_next)
                pieces.append((t, s, v, acc))
                dt = t_reach - t
                s += v * dt + 0.5 * acc * dt * dt
                v = v + acc * dt
                t = t_reach
            if t < t_next:
                pieces.append((t, s, v, 0.0))
                s += v * (t_next - t)
                t = t_next
        return pieces

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Arc length and speed ``([T], [T])`` at ``times`` ``[T]`` (seconds, >= 0)."""
        times = np.asarray(times, dtype=np.float64)
        pieces = self._pieces(float(times.max(initial=0.0)))
        starts = np.array([p[0] for p in pieces])
        idx = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(pieces) - 1)
        t0 = starts[idx]
        s0 = np.array([p[1] for p in pieces])[idx]
        v0 = np.array([p[2] for p in pieces])[idx]
        acc = np.array([p[3] for p in pieces])[idx]
        dt = times - t0
        speed = np.maximum(v0 + acc * dt, 0.0)
        return s0 + v0 * dt + 0.5 * acc * dt * dt, speed


@dataclass(frozen=True)
class Motion:
    """A path, a speed profile and the intended behaviour label.

    Attributes:
        path: the path followed.
        profile: the speed profile along it.
        behavior: intended behaviour (``straight``, ``turn_left``, ``stop``, ``parked``, ``crossing``...).
    """

    path: Path
    profile: SpeedProfile
    behavior: str

    def sample(self, times: np.ndarray) -> dict[str, np.ndarray]:
        """Sampled trajectory: ``xy [T, 2]``, ``heading [T]``, ``speed [T]``, ``s [T]``."""
        s, v = self.profile.sample(times)
        return {
            "xy": self.path.position(s),
            "heading": self.path.heading(s),
            "speed": v,
            "s": s,
        }


# ---------------------------------------------------------------------------------------------- vehicles
def drive(layout: RoadLayout, arm: str, lane: int, turn: str, speed: float, t_junction: float) -> Motion:
    """Constant-speed drive along a route, reaching the stop line at time ``t_junction`` (may be < 0)."""
    path = route(layout, arm, lane, turn)
    s0 = path.marks["junction_in"] - speed * t_junction
    label = {"straight": "straight", "left": "turn_left", "right": "turn_right"}[turn]
    return Motion(path, SpeedProfile(s0, speed), label)


def stop_at_line(
    layout: RoadLayout, arm: str, lane: int, speed: float, decel: float, t_brake: float, gap: float, length: float
) -> Motion:
    """Drive, brake at ``t_brake`` with ``decel`` and come to rest with the front ``gap`` metres before the stop line.

    ``length`` is the vehicle length (the path point is the box centre).
    """
    path = route(layout, arm, lane, "straight")
    s_rest = path.marks["stop"] - gap - length / 2.0
    s0 = s_rest - speed * speed / (2.0 * decel) - speed * t_brake
    return Motion(path, SpeedProfile(s0, speed, ((t_brake, -decel, 0.0),)), "stop")


def waiting(layout: RoadLayout, arm: str, lane: int, gap: float, length: float) -> Motion:
    """Standing still in a lane, the front ``gap`` metres before the stop line (queued traffic)."""
    path = route(layout, arm, lane, "straight")
    return Motion(path, SpeedProfile(path.marks["stop"] - gap - length / 2.0, 0.0), "stopped")


def slow_down(
    layout: RoadLayout, arm: str, lane: int, turn: str, speed: float, t_junction: float, t_brake: float, factor: float
) -> Motion:
    """Drive a route and decelerate (2 m/s^2) from ``t_brake`` to ``factor * speed``."""
    path = route(layout, arm, lane, turn)
    s0 = path.marks["junction_in"] - speed * t_junction
    return Motion(path, SpeedProfile(s0, speed, ((t_brake, -2.0, factor * speed),)), "slow_down")


def change_lanes(
    layout: RoadLayout,
    arm: str,
    lane_from: int,
    lane_to: int,
    speed: float,
    t_change: float,
    change_len: float,
    s_change: float,
) -> Motion:
    """Drive straight along the road of ``arm`` and change lanes starting at time ``t_change``.

    ``s_change`` is where the manoeuvre starts as a signed along-road distance *before* the stop line
    (negative values lie past the junction).
    """
    s_start = ROUTE_REACH - s_change
    path = lane_change_route(layout, arm, lane_from, lane_to, s_start, change_len)
    s0 = path.marks["change_start"] - speed * t_change
    label = "lane_change_left" if _is_left_change(layout, arm, lane_from, lane_to) else "lane_change_right"
    return Motion(path, SpeedProfile(s0, speed), label)


def _is_left_change(layout: RoadLayout, arm: str, lane_from: int, lane_to: int) -> bool:
    # inbound lanes: lane 0 is next to the centre line, i.e. the leftmost one for right-hand traffic
    return lane_to < lane_from


def parked(layout: RoadLayout, arm: str, inbound: bool, s_along: float) -> Motion:
    """Parked in the kerbside strip of a horizontal arm at along-arm distance ``s_along``, facing traffic direction."""
    d, n = arm_dir(arm), arm_normal(arm)
    off = layout.parking_offset(arm, inbound)
    p = layout.to_world(d * s_along + n * off)
    direction = -d if inbound else d
    path = polyline_path(np.stack([p - 5.0 * direction, p + 5.0 * direction]))
    return Motion(path, SpeedProfile(5.0, 0.0), "parked")


# ---------------------------------------------------------------------------------------------- pedestrians
def cross_street(
    layout: RoadLayout, arm: str, to_left: bool, lateral0: float, offset_in_crosswalk: float, speed: float
) -> Motion:
    """Walk across ``arm`` on its crosswalk.

    Args:
        to_left: walk towards ``+arm_normal(arm)`` (the inbound side) when true.
        lateral0: lateral position (along ``arm_normal``) at ``t = 0``.
        offset_in_crosswalk: along-arm position inside the crosswalk, in ``[0, 1]``.
        speed: walking speed, m/s.
    """
    d, n = arm_dir(arm), arm_normal(arm)
    s0, s1 = layout.crosswalk_range(arm)
    along = s0 + (0.15 + 0.7 * offset_in_crosswalk) * (s1 - s0)
    far = layout.half_width(arm) + layout.sidewalk_w * 0.6
    sign = 1.0 if to_left else -1.0
    a = layout.to_world(d * along - sign * n * (far + 30.0))
    b = layout.to_world(d * along + sign * n * (far + 30.0))
    path = polyline_path(np.stack([a, b]))
    s_start = far + 30.0 + sign * lateral0
    # stop walking once the far sidewalk is reached
    t_arrive = max((far - sign * lateral0) / speed, 0.0)
    return Motion(path, SpeedProfile(s_start, speed, ((t_arrive, -3.0, 0.0),)), "crossing")


def walk_sidewalk(
    layout: RoadLayout, arm: str, inbound_side: bool, s_along0: float, outward: bool, speed: float, lane_pos: float
) -> Motion:
    """Walk along the sidewalk of ``arm`` (the side next to its inbound or outbound lanes).

    ``lane_pos`` in ``[0, 1]`` places the walker across the sidewalk width; ``outward`` walks away
    from the junction.
    """
    d, n = arm_dir(arm), arm_normal(arm)
    sign = 1.0 if inbound_side else -1.0
    lat = sign * (layout.half_width(arm) + (0.25 + 0.5 * lane_pos) * layout.sidewalk_w)
    direction = d if outward else -d
    p0 = layout.to_world(d * s_along0 + n * lat)
    path = polyline_path(np.stack([p0 - 50.0 * direction, p0 + 200.0 * direction]))
    return Motion(path, SpeedProfile(50.0, speed), "walking")


def stand(position: np.ndarray, heading: float) -> Motion:
    """Standing still at world ``position`` ``[2]`` facing ``heading``."""
    direction = np.array([np.cos(heading), np.sin(heading)])
    path = polyline_path(np.stack([position - direction, position + direction]))
    return Motion(path, SpeedProfile(1.0, 0.0), "standing")


def static_at(position: np.ndarray, heading: float) -> Motion:
    """A static object at world ``position`` ``[2]`` with yaw ``heading``."""
    m = stand(position, heading)
    return Motion(m.path, m.profile, "static")
