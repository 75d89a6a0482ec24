"""A short bird's-eye animation of an edit: the log on the left, the edited and refined scenario on the right.

    frames = bev_animation_frames(log.map_features, edited.original_states, edited.states, title=prompt)
    video = encode_mp4(frames, fps=bev_fps(edited.states))   # storage.pictures

Both panels share one view (``viz.bev.bev_extent``) and step together, so a person sees who yielded to whom:
an agent that reacted to the edit is green on the right and where the log had it on the left.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.types import MapFeature
from simsplat_core.viz.bev import bev_extent, edit_bev

#: Pixels of one square panel.
PANEL_PX = 400


def bev_fps(states: AgentStates) -> float:
    """Frames per second that play ``states`` in real time (10 when the steps carry no time)."""
    dt = np.diff(states.times)
    return float(1.0 / np.median(dt)) if len(dt) and np.median(dt) > 0 else 10.0


def bev_animation_frames(map_features: tuple[MapFeature, ...] | list[MapFeature], before: AgentStates,
                         after: AgentStates, *, title: str = "", size: int = PANEL_PX, every: int = 1
                         ) -> list[np.ndarray]:
    """``[size, 2 * size, 3]`` uint8 RGB frames, one per ``every``-th step: log (left), edited + refined (right).

    Raises:
        ValueError: ``before`` and ``after`` have different steps.
    """
    if before.num_steps != after.num_steps:
        raise ValueError(f"bev_animation_frames: before has {before.num_steps} steps, after {after.num_steps}")
    extent = bev_extent(before, after)
    frames = []
    for step in range(0, after.num_steps, max(int(every), 1)):
        left = edit_bev(map_features, before, before, step=step, title="log", size=size, extent=extent)
        right = edit_bev(map_features, before, after, step=step, title=(title or "edited")[:48], size=size,
                         extent=extent)
        left[:, -2:] = 255  # a white seam between the panels
        frames.append(np.concatenate([left, right], axis=1))
    return frames
