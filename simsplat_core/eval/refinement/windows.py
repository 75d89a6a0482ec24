"""Every 9.1 s window of a real log, so that a log's rows average over several rollouts.

A window is :data:`WINDOW_STEPS` steps (91 at 10 Hz: Waymo Open Motion's 1.1 s of history and 8 s of future)
starting every ``stride`` steps (:data:`DEFAULT_STRIDE`), as long as it fits in the log; a log shorter than one
window is its only window. Each window is a :class:`RealScenario` of its own (times restart at 0, ``seq_id``
``"<log>@<first step>"``, the ego fixed as in the whole log); agents absent from a window are dropped, the ego
always kept.

    scenarios = [w for s in scenarios for w in windows_of(s, stride=10)]
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from simsplat_core.eval.refinement.real import RealScenario
from simsplat_core.scenario.agents import EGO_ID, AgentStates

#: Steps of one window: 9.1 s at 10 Hz.
WINDOW_STEPS = 91
#: Steps between consecutive windows' starts.
DEFAULT_STRIDE = 10


def window_starts(num_steps: int, stride: int = DEFAULT_STRIDE, length: int = WINDOW_STEPS) -> list[int]:
    """First steps of every window of ``length`` steps, ``stride`` apart, within ``num_steps`` (``[0]`` when the
    log is shorter than one window).

    Raises:
        ValueError: ``stride`` or ``length`` below 1 (named).
    """
    if stride < 1:
        raise ValueError(f"window stride must be at least 1 step, got {stride}")
    if length < 1:
        raise ValueError(f"window length must be at least 1 step, got {length}")
    return list(range(0, num_steps - length + 1, stride)) or [0]


def slice_steps(states: AgentStates, first: int, stop: int) -> AgentStates:
    """``states`` over steps ``[first, stop)`` with times from 0; agents valid nowhere in it are dropped, the ego
    kept."""
    valid = states.valid[:, first:stop]
    keep = [r for r in range(states.num_agents) if valid[r].any() or states.object_ids[r] == EGO_ID]
    cut = replace(states, frame_idx=states.frame_idx[first:stop], times=states.times[first:stop] - states.times[first],
                  xy=states.xy[:, first:stop], z=states.z[:, first:stop], heading=states.heading[:, first:stop],
                  speed=states.speed[:, first:stop], valid=valid)
    return cut.take(np.array(keep, dtype=np.int64))


def windows_of(scenario: RealScenario, stride: int = DEFAULT_STRIDE, length: int = WINDOW_STEPS) -> list[RealScenario]:
    """Every window of ``scenario`` (module docstring); the whole scenario when it is a single window."""
    n = scenario.states.num_steps
    starts = window_starts(n, stride, length)
    if starts == [0] and n <= length:
        return [scenario]
    return [replace(scenario, seq_id=f"{scenario.seq_id}@{first}",
                    states=slice_steps(scenario.states, first, min(first + length, n))) for first in starts]


__all__ = ["DEFAULT_STRIDE", "WINDOW_STEPS", "slice_steps", "window_starts", "windows_of"]
