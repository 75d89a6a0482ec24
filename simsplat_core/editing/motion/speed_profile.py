"""Longitudinal motion along a route: jerk-limited speed tracking, stops at a distance or a time, holds,
gap keeping to a leader (IDM), speed caps ahead (curves).

The planner integrates arc length ``s``, signed speed ``v`` and acceleration ``a`` in small substeps. Each
substep the acceleration moves toward a wanted value by at most ``jerk * dt`` and stays within
``[-hard_decel, max_accel]``, so the plan never exceeds its limits:

* speed tracking: toward the reference ``v_ref(t)`` with the time-optimal jerk-limited law
  ``a* = sign(dv) sqrt(2 jerk |dv|)`` (reaches the reference without overshoot);
* speed caps ahead (``SpeedCaps``: e.g. curvature-limited speeds along the route) lower the reference to
  what comfortable braking still allows;
* leaders (``LeaderTrack``: a followed agent, traffic on the route) add the Intelligent Driver Model's
  acceleration towards each one ahead (the smallest acceleration wins), except traffic entering the route
  behind the plan and traffic the agent's own log kept pace with while the plan stays behind that log;
* stops are planned, not tracked: once a comfortable jerk-limited braking profile (:func:`brake_segments`:
  jerk ramp to a peak deceleration, hold, ramp back to zero exactly at standstill) would need the distance
  (or time) that is left, the decelerations are solved so that the agent comes to rest exactly there, and it
  then stays at rest.

Units: metres, seconds, m/s, m/s^2, m/s^3. Times are seconds on the log's axis.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: Substep of the integration, seconds (10 per 10 Hz log step).
SUBSTEP_S = 0.01
#: A stop solved by bisection is this close to the wanted distance / time (m / s).
_SOLVE_TOL = 1e-4
#: A plan this far ahead of its own log position still counts as behind it (``LeaderTrack.log_s``), m.
LOG_COVER_TOL_M = 0.5


@dataclass(frozen=True)
class LongitudinalLimits:
    """Bounds the planner keeps.

    Attributes:
        max_speed_mps: forward speed bound.
        max_reverse_mps: backward speed bound.
        max_accel_mps2: acceleration when speeding up.
        comfort_decel_mps2: deceleration of ordinary slowing down and stops.
        hard_decel_mps2: deceleration bound of hard braking (and of stops that need more than comfort).
        jerk_mps3: jerk of ordinary manoeuvres; hard_jerk_mps3: of hard braking.
        lateral_accel_mps2: curve speeds are capped to ``sqrt(lateral_accel / curvature)``.
    """

    max_speed_mps: float = 30.0
    max_reverse_mps: float = 4.0
    max_accel_mps2: float = 2.5
    comfort_decel_mps2: float = 3.0
    hard_decel_mps2: float = 8.0
    jerk_mps3: float = 5.0
    hard_jerk_mps3: float = 15.0
    lateral_accel_mps2: float = 2.5


#: Cars: well inside the validation bounds of ``scenario.metrics.DEFAULT_LIMITS``.
VEHICLE_LIMITS = LongitudinalLimits()
#: People: a brisk start and stop within a second.
PEDESTRIAN_LIMITS = LongitudinalLimits(max_speed_mps=6.0, max_reverse_mps=1.5, max_accel_mps2=1.5,
                                       comfort_decel_mps2=2.0, hard_decel_mps2=3.5, jerk_mps3=4.0,
                                       hard_jerk_mps3=8.0, lateral_accel_mps2=math.inf)


# ---------------------------------------------------------------------------------- jerk profiles
Segment = tuple[float, float]  # (duration s, jerk m/s^3)


def integrate(s: float, v: float, a: float, segments: list[Segment]) -> tuple[float, float, float, float]:
    """``(s, v, a, duration)`` after piecewise-constant-jerk ``segments`` from ``(s, v, a)``."""
    total = 0.0
    for dur, jerk in segments:
        s += v * dur + a * dur * dur / 2.0 + jerk * dur ** 3 / 6.0
        v += a * dur + jerk * dur * dur / 2.0
        a += jerk * dur
        total += dur
    return s, v, a, total


def brake_segments(v: float, a: float, decel: float, jerk: float) -> list[Segment]:
    """Jerk segments taking forward speed ``v >= 0`` and acceleration ``a`` to rest (``v = a = 0``) with a
    peak deceleration of at most ``decel``: ramp to the peak at ``jerk``, hold it, ramp back to zero as
    the speed reaches zero. Where even ramping ``a`` straight back to zero overshoots standstill (braking
    harder than needed at a low speed), that ramp alone (the caller clamps at rest)."""
    v, decel = max(v, 0.0), max(decel, 1e-6)
    peak = min(decel, math.sqrt(jerk * v + a * a / 2.0))
    if peak < 1e-9:
        return []
    if a >= -peak:
        t1, j1 = (a + peak) / jerk, -jerk
    else:
        if v < a * a / (2.0 * jerk):
            return [(-a / jerk, jerk)]
        t1, j1 = (-peak - a) / jerk, jerk
    v1 = v + a * t1 + j1 * t1 * t1 / 2.0
    t2 = max(0.0, (v1 - peak * peak / (2.0 * jerk)) / peak)
    return [(t1, j1), (t2, 0.0), (peak / jerk, jerk)]


def brake_distance(v: float, a: float, decel: float, jerk: float) -> float:
    """Distance to rest of :func:`brake_segments`."""
    return integrate(0.0, v, a, brake_segments(v, a, decel, jerk))[0]


def brake_time(v: float, a: float, decel: float, jerk: float) -> float:
    """Time to rest of :func:`brake_segments`."""
    return integrate(0.0, v, a, brake_segments(v, a, decel, jerk))[3]


def _solve_decel(measure: Callable[[float], float], want: float, lo: float, hi: float) -> float:
    """The peak deceleration in ``[lo, hi]`` whose ``measure`` (decreasing in it) equals ``want``."""
    if measure(lo) <= want:
        return lo
    if measure(hi) >= want:
        return hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if measure(mid) > want:
            lo = mid
        else:
            hi = mid
        if hi - lo < _SOLVE_TOL:
            break
    return hi


def stopping_distance(v: float, limits: LongitudinalLimits, hard: bool = False) -> float:
    """Shortest distance to rest from speed ``|v|`` (zero acceleration) within the comfort (or hard) limits."""
    decel, jerk = ((limits.hard_decel_mps2, limits.hard_jerk_mps3) if hard
                   else (limits.comfort_decel_mps2, limits.jerk_mps3))
    return brake_distance(abs(v), 0.0, decel, jerk)


# ---------------------------------------------------------------------------------- plan inputs
@dataclass(frozen=True)
class StopTarget:
    """Where / when to come to rest (at most one of ``at_s`` / ``at_time``; neither: as soon as possible).

    Attributes:
        at_s: arc length to stop at (the agent's reference point, forward motion).
        at_time: time by which to be at rest (braking starts as late as comfort allows).
        hard: brake with the hard limits (``brake_hard``) instead of comfort.
    """

    at_s: float | None = None
    at_time: float | None = None
    hard: bool = False


@dataclass(frozen=True)
class SpeedCaps:
    """Speed bounds at arc lengths along the route (``v <= cap_v[k]`` when passing ``cap_s[k]``).

    Attributes:
        s: ``[K]`` increasing arc lengths; v: ``[K]`` speed bounds there, m/s.
    """

    s: np.ndarray
    v: np.ndarray

    def allowed(self, s_now: float, decel: float) -> float:
        """Highest speed at ``s_now`` from which braking at ``decel`` meets every cap ahead."""
        ahead = self.s >= s_now
        if not ahead.any():
            return math.inf
        return float(np.sqrt(self.v[ahead] ** 2 + 2.0 * decel * (self.s[ahead] - s_now)).min())


@dataclass(frozen=True)
class LeaderTrack:
    """Agents on the same route to keep a gap to: their arc lengths and speeds at the step times, where they
    are on the route (or about to enter it). Every agent ahead (centre beyond the planned agent's) adds the
    IDM acceleration towards it; the smallest wins (:meth:`accel`). Two exceptions keep the plan from
    braking for what cannot be in its way:

    * an agent about to enter the route (``enter_t`` later than now) does not bind a plan that, at its
      current speed, is past the entry point by the gap before the agent gets there (it enters behind);
    * with the planned agent's own log along the route (``log_s``), an agent ahead of that log position binds
      only as far as the log did (``log_cover``): a plan at or behind its log may follow the log as closely as
      the log followed it (the log drove there and did not hit it); a slowed car does not brake for the
      traffic its log kept pace with.

    Attributes:
        s: ``[L, T]`` arc length of each agent's centre along the route; v: ``[L, T]`` its speed along it.
        present: ``[L, T]`` bool, the agent exists and is on the route (or about to enter it).
        gap_m: ``[L]`` centre-to-centre distance at which the planned agent would touch it (half lengths
            summed) plus the standstill gap to keep.
        headway_s: time gap kept at speed.
        enter_t: ``[L, T]`` time the agent is on the route: the step's own time where it is, a later time
            where it is about to enter (``None``: every present agent is on the route).
        log_s: ``[T]`` arc length of the planned agent's own log centre along the route, NaN where the log is
            not on it; log_v: ``[T]`` its speed along it (``None``: no log, e.g. an inserted agent).
        log_cover: ``[L]`` bool, agents the log exception applies to (traffic; not a followed leader).
    """

    s: np.ndarray
    v: np.ndarray
    present: np.ndarray
    gap_m: np.ndarray
    headway_s: float = 1.5
    enter_t: np.ndarray | None = None
    log_s: np.ndarray | None = None
    log_v: np.ndarray | None = None
    log_cover: np.ndarray | None = None

    def accel(self, times: np.ndarray, t: float, s_now: float, v: float, v_des: float,
              lim: LongitudinalLimits) -> float | None:
        """Acceleration towards the agents ahead of ``s_now`` at time ``t`` (interpolated between steps) for a
        plan at speed ``v`` wanting ``v_des`` (class docstring), ``None`` when none binds."""
        k = int(np.clip(np.searchsorted(times, t), 1, len(times) - 1))
        w = float(np.clip((t - times[k - 1]) / (times[k] - times[k - 1]), 0.0, 1.0))
        here = self.present[:, k - 1] & self.present[:, k]
        s = (1 - w) * self.s[:, k - 1] + w * self.s[:, k]
        ahead = here & (s > s_now)
        if self.enter_t is not None:  # entering behind a plan that is past the entry point by then
            enter = self.enter_t[:, k]
            ahead &= ~((enter > t) & (s_now + max(v, 0.0) * (enter - t) >= s + self.gap_m))
        if not ahead.any():
            return None
        v_lead = (1 - w) * self.v[:, k - 1] + w * self.v[:, k]
        acc = np.array([_idm(v, v_des, float(s[j] - s_now - self.gap_m[j]), float(v_lead[j]), self, lim)
                        if ahead[j] else np.inf for j in range(len(s))])
        covered = self._log_cover(k, w, s_now, v, s, lim)
        if covered is not None:
            a_log, cover = covered
            acc = np.where(ahead & cover, np.maximum(acc, a_log), acc)
        return float(acc.min())

    def _log_cover(self, k: int, w: float, s_now: float, v: float, s: np.ndarray,
                   lim: LongitudinalLimits) -> tuple[float, np.ndarray] | None:
        """``(acceleration keeping the plan behind its log, [L] agents ahead of the log it applies to)``, ``None``
        when the log is not on the route now or the plan is ahead of it."""
        if self.log_s is None or self.log_v is None or self.log_cover is None:
            return None
        s_log = (1 - w) * self.log_s[k - 1] + w * self.log_s[k]
        v_log = (1 - w) * self.log_v[k - 1] + w * self.log_v[k]
        if not (np.isfinite(s_log) and np.isfinite(v_log)) or s_now > s_log + LOG_COVER_TOL_M:
            return None
        allowed = v_log + math.sqrt(2.0 * lim.comfort_decel_mps2 * max(s_log - s_now, 0.0))
        a_log = float(np.clip(_track(allowed - v, lim.jerk_mps3), -lim.hard_decel_mps2, lim.max_accel_mps2))
        return a_log, self.log_cover & (s > s_log)


@dataclass(frozen=True)
class SpeedPlan:
    """The plan at the step times.

    Attributes:
        s: ``[T]`` arc length; v: ``[T]`` signed speed; a: ``[T]`` acceleration. Steps before the start
            time extrapolate the start state backwards at constant speed.
        stopped_at: time the planned stop came to rest (``None``: no stop, or not within the steps).
    """

    s: np.ndarray
    v: np.ndarray
    a: np.ndarray
    stopped_at: float | None = None


def _track(dv: float, jerk: float) -> float:
    """Acceleration of the time-optimal jerk-limited approach to a speed ``dv`` away."""
    return math.copysign(math.sqrt(2.0 * jerk * abs(dv)), dv)


def _idm(v: float, v_des: float, gap: float, v_lead: float, lead: LeaderTrack, lim: LongitudinalLimits) -> float:
    """Acceleration for net ``gap`` (m) to a leader at ``v_lead`` by the Improved Intelligent Driver Model
    (Treiber & Kesting, *Traffic Flow Dynamics*, sec. 11.3.7): like the IDM, but an agent at its wanted speed
    with more than the wanted gap ahead holds that speed. (The plain IDM brakes below ``v_des`` behind any
    leader within a few headways, so a car asked to drive at a speed never held it behind traffic that leaves
    it room.)"""
    if gap <= 0.05:
        return -lim.hard_decel_mps2
    a_max, b = lim.max_accel_mps2, lim.comfort_decel_mps2
    star = max(0.0, v * lead.headway_s + v * (v - v_lead) / (2.0 * math.sqrt(a_max * b)))
    z = star / gap
    v_pos, v0 = max(v, 0.0), max(v_des, 0.1)
    if v_pos <= v0:
        free = a_max * (1.0 - (v_pos / v0) ** 4)
        if z >= 1.0:
            return a_max * (1.0 - z * z)
        return 0.0 if free <= 1e-9 else free * (1.0 - z ** (2.0 * a_max / free))
    free = -b * (1.0 - (v0 / v_pos) ** (a_max * 4 / b))
    return free + a_max * (1.0 - z * z) if z >= 1.0 else free


def plan_speed(times: np.ndarray, *, t0: float, s0: float, v0: float, a0: float = 0.0,
               v_ref: Callable[[float], float], limits: LongitudinalLimits, stop: StopTarget | None = None,
               caps: SpeedCaps | None = None, leader: LeaderTrack | None = None) -> SpeedPlan:
    """Plan ``s, v, a`` on ``times [T]`` from the state ``(s0, v0, a0)`` at ``t0``.

    Args:
        v_ref: wanted signed speed at a time (negative: backwards); held at 0 it keeps the agent at rest.
        stop: a stop to make (see :class:`StopTarget`); after it the agent stays at rest.
        caps: speed bounds ahead (forward motion only).
        leader: agents to keep a gap to (IDM to the nearest ahead).

    Raises:
        ValueError: a stop at a distance that even hard braking cannot make (message gives both distances).
    """
    lim = limits
    times = np.asarray(times, dtype=np.float64)
    v0 = float(np.clip(v0, -lim.max_reverse_mps, lim.max_speed_mps))
    a0 = float(np.clip(a0, -lim.hard_decel_mps2, lim.max_accel_mps2))
    if stop is not None and stop.at_s is not None and v0 > 0:
        need = stopping_distance(v0, lim, hard=True)
        if stop.at_s - s0 < need - 0.05:
            raise ValueError(f"cannot stop within {max(stop.at_s - s0, 0.0):.1f} m: braking hard from "
                             f"{v0:.1f} m/s needs {need:.1f} m")
    out_s = s0 + v0 * (times - t0)
    out_v = np.full(len(times), v0)
    out_a = np.zeros(len(times))
    s, v, a, t = s0, v0, a0, t0
    braking: list[Segment] | None = None
    brake_t, brake_dir = 0.0, 1.0 if v0 >= 0 else -1.0
    final = True  # the braking in progress is the requested stop (not a stop of the reference speed)
    stopped_at: float | None = None
    hard = stop is not None and stop.hard
    jerk_brake = lim.hard_jerk_mps3 if hard else lim.jerk_mps3
    decel_brake = lim.hard_decel_mps2 if hard else lim.comfort_decel_mps2
    if stop is not None and stop.at_s is None and stop.at_time is None:
        braking, brake_t = _brake_now(v, a, decel_brake, jerk_brake), t
    k = int(np.searchsorted(times, t0, side="left"))
    while k < len(times):
        if times[k] <= t + 1e-9:  # record the state at this step
            out_s[k], out_v[k], out_a[k] = s, v, a
            k += 1
            continue
        dt = min(SUBSTEP_S, float(times[k]) - t)
        if stopped_at is not None:
            t += dt
            continue
        if braking is None and stop is not None and abs(v) > 1e-6:
            braking = _maybe_start_braking(s, v, a, t, stop, lim)
            brake_t, brake_dir, final = t, 1.0 if v >= 0 else -1.0, True
        if braking is not None:
            pieces, done = _window(braking, t - brake_t, dt)
            s, v, a, _ = integrate(s, v, a, pieces)
            t += dt
            if done or v * brake_dir < 0:  # at rest (or a rounding past it)
                v, a = 0.0, 0.0
                if final:
                    stopped_at = t
                braking = None
            continue
        target = float(np.clip(v_ref(t), -lim.max_reverse_mps, lim.max_speed_mps))
        if target == 0.0 and abs(v) > 1e-6 and leader is None:  # come to rest by a planned (soft) stop
            braking, brake_t, brake_dir, final = _brake_now(v, a, lim.comfort_decel_mps2, lim.jerk_mps3), t, \
                (1.0 if v >= 0 else -1.0), False
            continue
        s, v, a = _track_substep(s, v, a, t=t, dt=dt, target=target, times=times, lim=lim, caps=caps, leader=leader)
        t += dt
    return SpeedPlan(out_s, out_v, out_a, stopped_at)


def _track_substep(s: float, v: float, a: float, *, t: float, dt: float, target: float, times: np.ndarray,
                   lim: LongitudinalLimits, caps: SpeedCaps | None, leader: LeaderTrack | None
                   ) -> tuple[float, float, float]:
    """One substep of ``dt`` from ``(s, v, a)`` at ``t`` towards the signed speed ``target``, under the speed
    ``caps`` ahead and the IDM gap to ``leader``, within the jerk and acceleration ``lim``; stops at rest
    instead of passing through zero speed. Returns the new ``(s, v, a)``."""
    if caps is not None and target > 0:
        target = min(target, caps.allowed(s, 0.8 * lim.comfort_decel_mps2))
    want = float(np.clip(_track(target - v, lim.jerk_mps3), -lim.comfort_decel_mps2, lim.max_accel_mps2))
    if leader is not None:
        lead = leader.accel(times, t, s, v, max(target, 0.1), lim)
        if lead is not None:
            want = min(want, lead)
    jerk_lim = lim.hard_jerk_mps3 if want < -lim.comfort_decel_mps2 else lim.jerk_mps3
    a_new = float(np.clip(want, a - jerk_lim * dt, a + jerk_lim * dt))
    a_new = float(np.clip(a_new, -lim.hard_decel_mps2, lim.max_accel_mps2))
    v_new = v + 0.5 * (a + a_new) * dt
    if (v >= 0 >= v_new and target >= 0) or (v <= 0 <= v_new and target <= 0):  # rest, not through zero
        if v_new != 0.0 or a_new * target <= 0:
            v_new, a_new = 0.0, 0.0
    return s + 0.5 * (v + v_new) * dt, v_new, a_new


def _brake_now(v: float, a: float, decel: float, jerk: float) -> list[Segment]:
    """Brake segments for signed speed ``v`` (mirrored for backwards motion)."""
    sign = 1.0 if v >= 0 else -1.0
    return [(d, sign * j) for d, j in brake_segments(abs(v), sign * a, decel, jerk)]


def _maybe_start_braking(s: float, v: float, a: float, t: float, stop: StopTarget,
                         lim: LongitudinalLimits) -> list[Segment] | None:
    """The braking segments to start now, or ``None`` while comfortable braking later still makes the stop."""
    sign = 1.0 if v >= 0 else -1.0
    speed, acc = abs(v), sign * a
    jerk = lim.hard_jerk_mps3 if stop.hard else lim.jerk_mps3
    comfort = lim.hard_decel_mps2 if stop.hard else lim.comfort_decel_mps2
    if stop.at_s is not None and v > 0:
        left = stop.at_s - s
        if brake_distance(speed, acc, comfort, jerk) < left - 0.5 * speed * SUBSTEP_S * 2:
            return None
        decel = _solve_decel(lambda d: brake_distance(speed, acc, d, jerk), max(left, 0.0), 0.05,
                             lim.hard_decel_mps2)
        if brake_distance(speed, acc, decel, jerk) > left + 0.05:  # try the hard jerk
            jerk = lim.hard_jerk_mps3
            decel = _solve_decel(lambda d: brake_distance(speed, acc, d, jerk), max(left, 0.0), 0.05,
                                 lim.hard_decel_mps2)
        return [(d, sign * j) for d, j in brake_segments(speed, acc, decel, jerk)]
    if stop.at_time is not None:
        left = stop.at_time - t
        if brake_time(speed, acc, comfort, jerk) < left - SUBSTEP_S:
            return None
        decel = _solve_decel(lambda d: brake_time(speed, acc, d, jerk), max(left, 0.0), 0.05, lim.hard_decel_mps2)
        if brake_time(speed, acc, decel, jerk) > left + 0.05:  # comfort jerk too slow: the hard jerk
            jerk = lim.hard_jerk_mps3
            decel = _solve_decel(lambda d: brake_time(speed, acc, d, jerk), max(left, 0.0), 0.05,
                                 lim.hard_decel_mps2)
        return [(d, sign * j) for d, j in brake_segments(speed, acc, decel, jerk)]
    return None


def _window(segments: list[Segment], start: float, dt: float) -> tuple[list[Segment], bool]:
    """The parts of ``segments`` within ``[start, start + dt]`` and whether they end inside it."""
    out: list[Segment] = []
    t0, end = 0.0, start + dt
    for dur, jerk in segments:
        lo, hi = max(t0, start), min(t0 + dur, end)
        if hi > lo:
            out.append((hi - lo, jerk))
        t0 += dur
    return out, t0 <= end + 1e-12
