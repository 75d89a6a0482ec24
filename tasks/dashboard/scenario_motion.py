"""A scenario card's motion: the bird's-eye view the browser animates (the log's and the edit's paths of every
agent, the road map), the agents the edit changed (``scenario.reactions.agent_changes``: edited, inserted, removed
and reacting agents, who yielded to whom) and the objects the edit grounded.

    motion = read_motion(store, run_id, seq_id, edit_id)   # ScenarioMotion(bev, changes, grounded)

Read from the log (``storage.logs.read_scene_log`` without images: tracks, map, captions), the edit's
``trajectories.parquet`` (``storage.edits.read_trajectories`` / ``trajectory_states``) and its
``delta/delta.json`` (inserted assets). Positions are world metres (x, y), rounded to centimetres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.reactions import EDIT_SOURCES, REMOVED, AgentChange, agent_changes
from simsplat_core.types import SceneLog
from storage.edits import read_edit_delta, read_trajectories, trajectory_states
from storage.logs import read_scene_log
from storage.store import ArtifactStore

#: Map kinds drawn in the BEV, bottom to top.
BEV_MAP_KINDS: tuple[str, ...] = ("drivable_area", "sidewalk", "crosswalk", "lane_marking", "lane", "road_edge")
#: Metres of road shown around the changed agents and the ego.
BEV_MARGIN_M = 15.0
#: Most points kept per map feature (evenly subsampled).
MAX_FEATURE_POINTS = 200

#: ``[x, y, heading]`` of one step, ``None`` where the agent does not exist.
Pose = list[float] | None


@dataclass(frozen=True)
class BevAgent:
    """One agent of the BEV.

    Attributes:
        object_id, category: the agent; source: its edit source (``log`` unchanged, ``edited``, ``inserted``,
            ``refined``, ``removed``); length, width: its box, metres.
        log: ``[T]`` its log poses (empty: inserted); edited: ``[T]`` its poses after the edit (empty: removed).
    """

    object_id: str
    category: str
    source: str
    length: float
    width: float
    log: list[Pose]
    edited: list[Pose]


@dataclass(frozen=True)
class MapShape:
    """One map feature: ``kind`` (``BEV_MAP_KINDS``), ``closed`` (a polygon), ``[P, 2]`` points."""

    kind: str
    closed: bool
    points: list[list[float]]


@dataclass(frozen=True)
class BevView:
    """What the BEV animation draws.

    Attributes:
        frames: ``[T]`` log frame index of each step; times: ``[T]`` seconds from the log's first frame.
        bounds: ``[x_min, y_min, x_max, y_max]`` metres: the changed agents and the ego, with a margin.
        agents: every agent, the unchanged ones first (drawn underneath).
        map: the road map.
    """

    frames: list[int]
    times: list[float]
    bounds: list[float]
    agents: list[BevAgent]
    map: list[MapShape]


@dataclass(frozen=True)
class GroundedObject:
    """An object the edit acted on.

    Attributes:
        object_id, category: the object; role: ``edited`` (its motion changed), ``inserted``, ``removed``.
        caption: the log's caption (``""`` for inserted ones); asset_id: the inserted asset (``""`` otherwise).
    """

    object_id: str
    category: str
    role: str
    caption: str
    asset_id: str


@dataclass(frozen=True)
class ScenarioMotion:
    """Attributes: bev: the animation's data; changes: the changed agents (who yielded to whom); grounded: the
    edit's own objects."""

    bev: BevView
    changes: list[AgentChange]
    grounded: list[GroundedObject]


def _poses(states: AgentStates, row: int) -> list[Pose]:
    return [[round(float(x), 2), round(float(y), 2), round(float(h), 3)] if ok else None
            for (x, y), h, ok in zip(states.xy[row], states.heading[row], states.valid[row])]


def _bev_agents(edited: AgentStates, log: AgentStates, changed: dict[str, str]) -> list[BevAgent]:
    out = []
    for k, oid in enumerate(edited.object_ids):
        j = log.index(oid) if oid in log.object_ids else None
        out.append(BevAgent(oid, edited.categories[k], edited.sources[k], float(edited.size[k, 0]),
                            float(edited.size[k, 1]), [] if j is None else _poses(log, j), _poses(edited, k)))
    for oid, source in changed.items():
        if source == REMOVED:
            j = log.index(oid)
            out.append(BevAgent(oid, log.categories[j], REMOVED, float(log.size[j, 0]), float(log.size[j, 1]),
                                _poses(log, j), []))
    return sorted(out, key=lambda a: a.source != "log")


def _bounds(agents: list[BevAgent], changed: dict[str, str]) -> list[float]:
    focus = [a for a in agents if a.object_id in changed or a.object_id == EGO_ID] or agents
    points = np.array([p[:2] for a in focus for p in (*a.log, *a.edited) if p is not None] or [[0.0, 0.0]])
    lo, hi = points.min(axis=0) - BEV_MARGIN_M, points.max(axis=0) + BEV_MARGIN_M
    return [round(float(v), 2) for v in (*lo, *hi)]


def _map(log: SceneLog) -> list[MapShape]:
    shapes = []
    for kind in BEV_MAP_KINDS:
        for feature in (f for f in log.map_features if f.kind == kind):
            pts = np.asarray(feature.points)[:, :2]
            if len(pts) > MAX_FEATURE_POINTS:
                pts = pts[np.linspace(0, len(pts) - 1, MAX_FEATURE_POINTS).astype(int)]
            shapes.append(MapShape(kind, kind in ("drivable_area", "sidewalk", "crosswalk"),
                                   np.round(pts, 2).tolist()))
    return shapes


def _grounded(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str, log: SceneLog,
              changes: list[AgentChange]) -> list[GroundedObject]:
    captions = {o.object_id: o.caption for o in log.objects}
    assets = {a.object_id: a.asset_id for a in read_edit_delta(store, run_id, seq_id, edit_id).delta.added}
    return [GroundedObject(c.object_id, c.category, c.source, captions.get(c.object_id, ""),
                           assets.get(c.object_id, "")) for c in changes if c.source in (*EDIT_SOURCES, REMOVED)]


def read_motion(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> ScenarioMotion:
    """The motion of one stored edit (module docstring).

    Raises:
        FileNotFoundError, CorruptArtifactError, SchemaError: the log, trajectories or delta is missing or does
            not decode (naming the file).
    """
    log = read_scene_log(store, seq_id, load_images=False)
    log_states = AgentStates.from_log(log)
    edited = trajectory_states(read_trajectories(store, run_id, seq_id, edit_id), log_states)
    changes = agent_changes(edited, log_states)
    changed = {c.object_id: c.source for c in changes}
    agents = _bev_agents(edited, log_states, changed)
    bev = BevView([int(f) for f in log_states.frame_idx], [round(float(t), 3) for t in log_states.times],
                  _bounds(agents, changed), agents, _map(log))
    return ScenarioMotion(bev, changes, _grounded(store, run_id, seq_id, edit_id, log, changes))


__all__ = ["BEV_MAP_KINDS", "BevAgent", "BevView", "GroundedObject", "MapShape", "ScenarioMotion", "read_motion"]
