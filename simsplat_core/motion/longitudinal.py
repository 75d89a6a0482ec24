"""Longitudinal control along the route: IDM+ with the log's speed profile as the free-road term.

IDM+ (Schakel et al. 2010) takes ``a = min(a_free, a_interaction)``. Here the free-road term tracks the
agent's desired (logged) speed profile ``v_ref`` -- with nobody in the way the agent reproduces its log --
catching up at no more than ``max(a, logged acceleration)``; the interaction term is IDM's
``a * (1 - (s*/gap)^2)`` with ``s* = s0 + max(0, v T + v dv / (2 sqrt(a b)))``. All per-agent parameters are
``[N]`` arrays (vehicles and pedestrians differ), every function is vectorised over agents.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from simsplat_core.motion.traffic_params import IDMParams

_EPS = 1e-6


@dataclass(frozen=True)
class IDMArrays:
    """``[N]`` IDM parameters per agent (fields as :class:`IDMParams`)."""

    time_headway: np.ndarray
    min_gap: np.ndarray
    max_accel: np.ndarray
    comfortable_decel: np.ndarray
    max_decel: np.ndarray
    clearance: np.ndarray
    min_time_headway: np.ndarray
    min_min_gap: np.ndarray

    @classmethod
    def per_agent(cls, params: list[IDMParams]) -> IDMArrays:
        """Stack one :class:`IDMParams` per agent."""
        return cls(*(np.array([getattr(p, f) for p in params], dtype=np.float64) for f in (
            "desired_time_headway_s", "min_gap_m", "max_accel_mps2", "comfortable_decel_mps2", "max_decel_mps2",
            "standstill_clearance_m", "min_time_headway_s", "min_standstill_gap_m")))

    def calibrated(self, v: np.ndarray, v_leader: np.ndarray, gap: np.ndarray) -> IDMArrays:
        """The parameters with ``T`` and ``s0`` lowered for agents whose observed ``gap [N]`` (at speed ``v``
        behind a leader at ``v_leader``) is below their desired gap: they keep the headway they drive with,
        no lower than ``min_time_headway`` / ``min_min_gap``."""
        has = np.isfinite(gap)
        g = np.where(has, gap, np.inf)
        min_gap = np.clip(g, self.min_min_gap, self.min_gap)
        dyn = v * (v - v_leader) / (2.0 * np.sqrt(self.max_accel * self.comfortable_decel))
        headway = (g - min_gap - np.maximum(dyn, 0.0)) / np.maximum(v, _EPS)
        headway = np.where(v > _EPS, np.clip(headway, self.min_time_headway, self.time_headway), self.time_headway)
        return replace(self, min_gap=min_gap, time_headway=headway)


def desired_gap(v: np.ndarray, dv: np.ndarray, p: IDMArrays) -> np.ndarray:
    """``[N]`` IDM desired gap ``s*`` at speed ``v`` closing on the leader at ``dv = v - v_leader``."""
    return p.min_gap + np.maximum(0.0, v * p.time_headway + v * dv / (2.0 * np.sqrt(p.max_accel * p.comfortable_decel)))


def interaction_accel(v: np.ndarray, v_leader: np.ndarray, gap: np.ndarray, p: IDMArrays) -> np.ndarray:
    """``[N]`` IDM interaction term ``a (1 - (s*/gap)^2)``; ``a`` where there is no leader (``gap = inf``)."""
    ratio = desired_gap(v, v - v_leader, p) / np.maximum(gap, _EPS)
    return np.where(np.isfinite(gap), p.max_accel * (1.0 - ratio**2), p.max_accel)


def free_accel(v: np.ndarray, v_ref: np.ndarray, v_ref_prev: np.ndarray, dt: float, p: IDMArrays) -> np.ndarray:
    """``[N]`` acceleration reaching the desired speed ``v_ref`` in one step, bounded by the hard-brake limit
    and by ``max(a, logged acceleration)`` (``(v_ref - v_ref_prev) / dt``)."""
    upper = np.maximum(p.max_accel, (v_ref - v_ref_prev) / dt)
    return np.clip((v_ref - v) / dt, -np.maximum(p.max_decel, (v_ref_prev - v_ref) / dt), upper)


def next_speed(v: np.ndarray, accel: np.ndarray, dt: float, gap: np.ndarray, p: IDMArrays) -> np.ndarray:
    """``[N]`` speed after one step: the acceleration (no less than the hard-brake limit) applied, never
    negative, and never carrying the agent closer than ``clearance`` to the obstacle ahead within the step
    (semi-implicit Euler: the step's distance is ``v_next * dt``)."""
    v_next = np.maximum(v + np.maximum(accel, -p.max_decel) * dt, 0.0)
    room = np.maximum(gap - p.clearance, 0.0) / dt
    return np.minimum(v_next, room)
