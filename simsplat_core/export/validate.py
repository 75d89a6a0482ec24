"""Re-validation of an exported scenario from its exported tracks, with the scenario layer's metrics.

What is checked is what the export itself could have broken, measured as the editor measures an edit
(``scenario.metrics.validate_agents``): the agents an edit changed (every track whose source is not ``"log"``)
against every agent of the window, for box overlaps, leaving the road and kinematic bounds, on the tracks and
map as written (after windowing, resampling and float32 rounding). Pairs of two logged agents are the log's own
overlaps and are not counted; an unedited log has no changed agent and passes.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.export.record import HEADING, LENGTH, VX, VY, ExportScenario, X, Y, Z
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import ValidationReport, validate_agents
from simsplat_core.types import MapFeature

#: Exported map kind -> the log model's kind, for the map context of the checks.
LOG_KIND_OF_KIND: dict[str, str] = {"lane": "lane", "road_edge": "road_edge", "road_line": "lane_marking",
                                    "crosswalk": "crosswalk"}


def exported_agent_states(s: ExportScenario) -> AgentStates:
    """The exported tracks as ``AgentStates`` (categories from the agent types, per-track box the median of its
    valid steps, signed speed along the heading from the velocity)."""
    states = s.states
    heading = states[..., HEADING]
    speed = states[..., VX] * np.cos(heading) + states[..., VY] * np.sin(heading)
    size = np.zeros((s.num_tracks, 3))
    for r in range(s.num_tracks):
        rows = states[r, s.valid[r], LENGTH:LENGTH + 3]
        size[r] = np.median(rows, axis=0) if len(rows) else (1.0, 1.0, 1.0)
    sources = s.track_sources or ("log",) * s.num_tracks
    ids = s.source_object_ids or tuple(str(t) for t in s.track_ids)
    return AgentStates(object_ids=tuple(ids), categories=tuple(s.agent_types), sources=tuple(sources),
                       node_ids=np.full(s.num_tracks, -1, np.int64), frame_idx=np.arange(s.num_steps),
                       times=np.asarray(s.timestamps_s, np.float64) - float(s.timestamps_s[0]),
                       xy=states[..., X:Y + 1].copy(), z=states[..., Z].copy(), heading=heading.copy(),
                       speed=speed, size=size, valid=s.valid.copy())


def exported_map_context(s: ExportScenario) -> MapContext:
    """The map context of the exported map features the checks use (lanes, road edges, lines, crosswalks)."""
    features = [MapFeature(f"{f.kind}_{f.feature_id}", LOG_KIND_OF_KIND[f.kind], np.asarray(f.points, np.float64))
                for f in s.map_features if f.kind in LOG_KIND_OF_KIND and len(f.points) >= 2]
    return MapContext.from_features(features)


def revalidate(s: ExportScenario, map_ctx: MapContext | None = None) -> ValidationReport:
    """Collisions, off-road and kinematics of the changed tracks of ``s`` (module docstring). ``map_ctx``: the
    exported map's context when the caller already built it (windows of one log share one map)."""
    states = exported_agent_states(s)
    rows = [r for r, src in enumerate(states.sources) if src != "log" and states.valid[r].any()]
    return validate_agents(states, map_ctx or exported_map_context(s), rows)
