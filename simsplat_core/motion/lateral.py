"""Lateral motion: a smooth offset from the route, and the MOBIL decision to shift into a neighbour lane.

Each driven agent carries one offset profile over arc length (not time: a stopped car does not slide
sideways): ``offset(s) = from + (to - from) * smoothstep((s - start) / length)``. It fades an agent's initial
offset from a lane-graph route out, and moves a vehicle by a lane width when MOBIL (Kesting, Treiber &
Helbing 2007) accepts a change around a blocked lane:

* incentive: ``a_new - a_old - p * (a_follower_old - a_follower_new) > a_th`` (``p`` politeness, the new
  follower's old acceleration taken as free driving, ``a``);
* safety: the new follower brakes no harder than ``b_safe``, and the move ends before the obstacle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_EPS = 1e-6


@dataclass
class OffsetProfiles:
    """``[N]`` offset profiles (mutable: the predictor replaces profiles when an agent changes lane).

    Attributes:
        start: arc length where the move starts; length: its length (m, ``> 0``).
        origin: offset before the move; target: offset after it (left positive, metres).
    """

    start: np.ndarray
    length: np.ndarray
    origin: np.ndarray
    target: np.ndarray

    def _u(self, rows: np.ndarray, s: np.ndarray) -> np.ndarray:
        return np.clip((s - self.start[rows]) / self.length[rows], 0.0, 1.0)

    def offset(self, rows: np.ndarray, s: np.ndarray) -> np.ndarray:
        """``[...]`` offset of agents ``rows`` at arc lengths ``s`` (same shape, or broadcasting)."""
        u = self._u(rows, s)
        return self.origin[rows] + (self.target[rows] - self.origin[rows]) * u * u * (3.0 - 2.0 * u)

    def slope(self, rows: np.ndarray, s: np.ndarray) -> np.ndarray:
        """``[...]`` d offset / d s there."""
        u = self._u(rows, s)
        return (self.target[rows] - self.origin[rows]) * 6.0 * u * (1.0 - u) / self.length[rows]

    def settled(self, s: np.ndarray) -> np.ndarray:
        """``[N]`` bool: every agent's move is over at its arc length ``s [N]``."""
        return s >= self.start + self.length

    def replace(self, rows: np.ndarray, start: np.ndarray, length: np.ndarray, origin: np.ndarray,
                target: np.ndarray) -> None:
        """New profiles for agents ``rows``."""
        self.start[rows], self.length[rows] = start, length
        self.origin[rows], self.target[rows] = origin, target


def mobil_gain(a_old: np.ndarray, a_new: np.ndarray, follower_free: np.ndarray, follower_new: np.ndarray,
               politeness: float) -> np.ndarray:
    """``[N]`` MOBIL incentive ``a_new - a_old - p (a_follower_old - a_follower_new)``."""
    return a_new - a_old - politeness * np.maximum(follower_free - follower_new, 0.0)


def change_length(v: np.ndarray, gap: np.ndarray, duration_s: float, min_length_m: float,
                  clearance_m: float) -> np.ndarray:
    """``[N]`` road length of a lane change: ``v * duration`` (at least ``min_length_m``), and it must end
    ``clearance_m`` before the obstacle ``gap`` ahead; ``nan`` where it cannot."""
    length = np.maximum(v * duration_s, min_length_m)
    room = gap - clearance_m
    length = np.where(length > room, room, length)
    return np.where(length >= min_length_m - _EPS, length, np.nan)
