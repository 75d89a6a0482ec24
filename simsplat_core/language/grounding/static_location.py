"""Where a static object is relative to the ego, for grounding "the stop sign ahead of us".

Moving objects get their location (sector and map context) from the trajectory aligner; static objects
(signs, cones, barriers) have no motion features, so without this every stop sign of a scene would tie on
"ahead of us" / "on the left". A static object's sector changes as the ego drives past it, so it gets a
distribution: the share of the steps at which it is within ``SIGHT_M`` of the ego (all its steps when it
never is) spent in each ``LOCATION_SECTOR`` class (``motion_labels.location_sector``, the labeller's
thresholds). It is derived from the log's geometry whenever a language scene meets its log (it is not
stored), and ``scoring.location_score`` reads it for nodes without motion features.

    scene = with_static_locations(scene, states)      # states: AgentStates of the scene's log
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from simsplat_core.language.motion_labels import LabelThresholds, location_sector
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.scenario.agents import EGO_ID, AgentStates

logger = logging.getLogger(__name__)

#: A static object counts towards its sectors at the steps where it is at most this far from the ego (m).
SIGHT_M = 60.0


def sector_shares(xy: np.ndarray, ego_xy: np.ndarray, ego_heading: np.ndarray, thresholds: LabelThresholds | None = None
                  ) -> dict[str, float]:
    """Share of steps per sector of a static object (module docstring).

    Args:
        xy: ``[T, 2]`` the object's world position at the steps where it exists.
        ego_xy: ``[T, 2]`` the ego's position at the same steps.
        ego_heading: ``[T]`` the ego's heading (rad).
    """
    th = thresholds or LabelThresholds()
    delta = np.asarray(xy, np.float64) - np.asarray(ego_xy, np.float64)  # [T, 2]
    if delta.shape[0] == 0:
        return {}
    cos, sin = np.cos(ego_heading), np.sin(ego_heading)
    rel = np.stack([cos * delta[:, 0] + sin * delta[:, 1], -sin * delta[:, 0] + cos * delta[:, 1]], axis=1)
    near = np.linalg.norm(rel, axis=1) <= SIGHT_M
    rows = rel[near] if near.any() else rel
    counts: dict[str, float] = {}
    for point in rows:
        name = location_sector(point, th)
        counts[name] = counts.get(name, 0.0) + 1.0
    return {name: n / len(rows) for name, n in counts.items()}


def with_static_locations(scene: LanguageScene, states: AgentStates) -> LanguageScene:
    """``scene`` with ``static_location`` set on every node without motion features whose object is an agent of
    ``states`` (by value; nodes already carrying one keep it)."""
    if EGO_ID not in states.object_ids:
        return scene
    ego = states.index(EGO_ID)
    nodes = []
    for node in scene.nodes:
        if node.motion is not None or node.static_location is not None or node.object_id not in states.object_ids:
            nodes.append(node)
            continue
        row = states.index(node.object_id)
        steps = states.valid[row] & states.valid[ego]
        shares = sector_shares(states.xy[row][steps], states.xy[ego][steps], states.heading[ego][steps])
        nodes.append(dataclasses.replace(node, static_location=shares or None))
    return dataclasses.replace(scene, nodes=tuple(nodes))


__all__ = ["SIGHT_M", "sector_shares", "with_static_locations"]
