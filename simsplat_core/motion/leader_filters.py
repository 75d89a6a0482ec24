"""Agents that are no leader although they stand in a driven agent's corridor, and mutual-leader deadlocks.

* parked obstacles the log passes: an unedited given agent whose logged box never moves farther than
  ``CorridorParams.parked_move_m`` (a parked car, a kerb obstacle) is no leader of an unedited agent whose
  logged route runs past it without touching it (the log drove by it; a labelled box often reaches into the
  lane); a log that drives into it (a scene built around an obstacle) keeps it a leader; a pedestrian standing
  still is no leader of an unedited pedestrian whose logged route runs past it even where their boxes touch
  (people squeeze past each other);
* companions: two unedited agents of one category moving side by side or one just behind the other at the same
  speed and heading at the last observed step (pedestrians walking together) travel in company:
  neither is the other's leader (``CorridorParams.company_*``);
* mutual leaders: two driven agents each the other's leader would wait for ever; the first in row order
  ignores the other (``mutual_leaders``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.motion.corridor import Pairs
from simsplat_core.motion.traffic_params import CorridorParams
from simsplat_core.scenario.agents import AgentStates


def parked_in_log(states: AgentStates, move_m: float) -> np.ndarray:
    """``[A]`` bool: the agent's logged box never moves farther than ``move_m`` from its first valid position."""
    out = np.zeros(states.num_agents, dtype=bool)
    for r in range(states.num_agents):
        steps = np.flatnonzero(states.valid[r])
        if steps.size:
            out[r] = float(np.linalg.norm(states.xy[r, steps] - states.xy[r, steps[0]], axis=1).max()) < move_m
    return out


def in_company(states: AgentStates, rows: np.ndarray, step: int, is_log: np.ndarray,
               params: CorridorParams) -> np.ndarray:
    """``[N, A]`` bool: driven agent ``rows[n]`` and agent ``a`` travel in company at ``step`` (both unedited,
    valid, moving, of the same category, centres within ``company_gap_m``, speeds and headings alike;
    ``CorridorParams``): a cyclist riding at walking pace among pedestrians is no companion of theirs."""
    v = states.speed[:, step]
    ok = states.valid[:, step] & is_log & (np.abs(v) >= params.company_speed_mps)
    d = np.linalg.norm(states.xy[rows, step][:, None] - states.xy[None, :, step], axis=-1)  # [N, A]
    dv = np.abs(v[rows][:, None] - v[None])
    dh = np.abs(wrap_angle(states.heading[rows, step][:, None] - states.heading[None, :, step]))
    out = ok[rows][:, None] & ok[None] & (d < params.company_gap_m) & (dv < params.company_speed_mps) \
        & (dh < np.deg2rad(params.company_heading_deg))
    category = np.array(states.categories)
    out &= category[rows][:, None] == category[None]
    out[np.arange(len(rows)), rows] = False
    return out


def mutual_leaders(leader: np.ndarray, driven_of: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``[N]`` bool: driven agent ``n`` follows driven agent ``m`` while ``m`` follows ``n`` and ``n < m`` (one of
    each mutual pair, the first in row order)."""
    other = np.where(leader >= 0, driven_of[np.maximum(leader, 0)], -1)  # [N] driven index of the leader
    has = other >= 0
    back = np.where(has, leader[np.maximum(other, 0)], -1)
    return has & (back == rows) & (np.arange(len(rows)) < other)


def passes_clear(states: AgentStates, rows: np.ndarray, others: np.ndarray) -> np.ndarray:
    """``[N, A]`` bool: the logged boxes of driven ``rows [N]`` never overlap agent ``a``'s box at its first
    valid pose (only the ``others [A]`` columns are computed, the rest ``False``); the overlap test is in that
    box's frame with both boxes aligned to it (a parked obstacle's extent, not a full collision check)."""
    out = np.zeros((len(rows), states.num_agents), dtype=bool)
    for a in np.flatnonzero(others).tolist():
        steps = np.flatnonzero(states.valid[a])
        if not steps.size:
            continue
        c, h = states.xy[a, steps[0]], states.heading[a, steps[0]]
        rel = states.xy[rows] - c  # [N, T, 2]
        along = rel[..., 0] * np.cos(h) + rel[..., 1] * np.sin(h)
        across = -rel[..., 0] * np.sin(h) + rel[..., 1] * np.cos(h)
        reach_l = (states.size[rows, 0] + states.size[a, 0])[:, None] / 2.0
        reach_w = (states.size[rows, 1] + states.size[a, 1])[:, None] / 2.0
        touch = (np.abs(along) < reach_l) & (np.abs(across) < reach_w) & states.valid[rows]
        out[:, a] = ~touch.any(axis=1)
    return out


@dataclass(frozen=True)
class IgnoredLeaders:
    """Which (driven agent, other agent) pairs are no leader (module docstring).

    Attributes:
        parked: ``[A]`` unedited given agents parked in the log (an inserted obstacle always counts).
        clear: ``[N, A]`` the driven agent's logged boxes never touch that parked agent.
        unedited: ``[N]`` driven agents that follow their own logged route.
        log_end: ``[N]`` arc length where each driven agent's logged route ends.
        company: ``[N, A]`` pairs travelling in company.
        walkers: ``[N, A]`` pairs of pedestrians.
    """

    parked: np.ndarray
    clear: np.ndarray
    unedited: np.ndarray
    log_end: np.ndarray
    company: np.ndarray
    walkers: np.ndarray

    @classmethod
    def of(cls, states: AgentStates, rows: np.ndarray, step: int, given: np.ndarray, is_log: np.ndarray,
           walking: np.ndarray, log_end: np.ndarray, params: CorridorParams) -> IgnoredLeaders:
        """The filters of driven ``rows [N]`` (``log_end [N]``, 0 for lane-graph routes) at the last observed
        ``step``; ``given`` / ``is_log`` / ``walking`` ``[A]``: agents not driven / unedited / pedestrians."""
        parked = given & is_log & parked_in_log(states, params.parked_move_m)
        return cls(parked=parked, clear=passes_clear(states, rows, parked),
                   unedited=is_log[rows] & (log_end > 0.0), log_end=log_end,
                   company=in_company(states, rows, step, is_log, params),
                   walkers=walking[rows][:, None] & walking[None])

    def pairs(self, pairs: Pairs) -> np.ndarray:
        """``[P]`` bool: the pair's other agent is no leader of its driven agent."""
        passable = self.clear[pairs.i, pairs.j] | self.walkers[pairs.i, pairs.j]
        passed = self.parked[pairs.j] & passable & self.unedited[pairs.i] \
            & (pairs.along < self.log_end[pairs.i])
        return passed | self.company[pairs.i, pairs.j]


__all__ = ["IgnoredLeaders", "in_company", "mutual_leaders", "parked_in_log", "passes_clear"]
