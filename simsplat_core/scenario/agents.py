"""All agents of a scenario as one struct of arrays over (agent, step), Waymax-style.

Metrics (``scenario.metrics``), the motion controller, refinement and the ``trajectories`` table all read
and write :class:`AgentStates`: per-agent rows, per-step columns and a validity mask, never lists of
objects. The ego is an agent too (``object_id`` :data:`EGO_ID`, ``source`` ``"log"``), so an inserted car
that drives into the ego is a collision like any other.

Frames: world frame of the log (metres, radians CCW from world +x). Steps are the log's frames.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from simsplat_core.geometry import yaw_of_rotation
from simsplat_core.types import SceneLog

#: ``object_id`` of the ego agent.
EGO_ID = "ego"
#: Ego box (length, width, height) when the log does not give one.
EGO_SIZE = (4.8, 2.0, 1.6)
#: ``source`` values of the ``trajectories`` table (DESIGN.md).
SOURCES: tuple[str, ...] = ("log", "edited", "inserted", "refined")


@dataclass(frozen=True)
class AgentStates:
    """``A`` agents over ``T`` steps.

    Attributes:
        object_ids: ``[A]`` ids (log ids kept; inserted agents get new ones).
        categories: ``[A]`` object categories (``vehicle``, ``pedestrian``, ``cyclist``, ``static``, ...).
        sources: ``[A]`` one of :data:`SOURCES`.
        node_ids: ``[A]`` int64 scene-graph node id, ``-1`` for agents without one (the ego, unreconstructed).
        frame_idx: ``[T]`` int64 log frame index of each step.
        times: ``[T]`` float64 seconds since the log's first frame.
        xy: ``[A, T, 2]`` float64 box centres.
        z: ``[A, T]`` float64 box-centre heights.
        heading: ``[A, T]`` float64 yaw, radians.
        speed: ``[A, T]`` float64 signed speed along the heading, m/s (negative when reversing).
        size: ``[A, 3]`` float64 box (length, width, height).
        valid: ``[A, T]`` bool, the agent exists at that step.
    """

    object_ids: tuple[str, ...]
    categories: tuple[str, ...]
    sources: tuple[str, ...]
    node_ids: np.ndarray
    frame_idx: np.ndarray
    times: np.ndarray
    xy: np.ndarray
    z: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    size: np.ndarray
    valid: np.ndarray

    def __post_init__(self) -> None:
        a, t = len(self.object_ids), len(self.times)
        for name, shape in (("categories", (a,)), ("sources", (a,)), ("node_ids", (a,)), ("frame_idx", (t,)),
                            ("xy", (a, t, 2)), ("z", (a, t)), ("heading", (a, t)), ("speed", (a, t)),
                            ("size", (a, 3)), ("valid", (a, t))):
            got = np.shape(getattr(self, name))
            if tuple(got) != shape:
                raise ValueError(f"AgentStates.{name} must be {list(shape)}, got {list(got)}")
        bad = sorted(set(self.sources) - set(SOURCES))
        if bad:
            raise ValueError(f"AgentStates.sources: unknown {bad}; expected one of {list(SOURCES)}")
        if len(set(self.object_ids)) != a:
            raise ValueError("AgentStates.object_ids must be unique")

    @property
    def num_agents(self) -> int:
        return len(self.object_ids)

    @property
    def num_steps(self) -> int:
        return len(self.times)

    def index(self, object_id: str) -> int:
        """Row of ``object_id``. Raises ``KeyError`` naming it."""
        try:
            return self.object_ids.index(object_id)
        except ValueError:
            raise KeyError(f"no agent {object_id!r} in the scenario") from None

    def index_of_node(self, node_id: int) -> int:
        """Row of the agent drawn by scene-graph node ``node_id``. Raises ``KeyError`` naming it."""
        rows = np.flatnonzero(self.node_ids == node_id)
        if rows.size == 0:
            raise KeyError(f"no agent for node {node_id} in the scenario")
        return int(rows[0])

    def take(self, rows: np.ndarray | list[int]) -> AgentStates:
        """The agents at ``rows`` (in that order)."""
        rows = np.asarray(rows, dtype=np.int64)
        pick = [int(r) for r in rows]
        return replace(self, object_ids=tuple(self.object_ids[r] for r in pick),
                       categories=tuple(self.categories[r] for r in pick),
                       sources=tuple(self.sources[r] for r in pick), node_ids=self.node_ids[rows],
                       xy=self.xy[rows], z=self.z[rows], heading=self.heading[rows], speed=self.speed[rows],
                       size=self.size[rows], valid=self.valid[rows])

    def without(self, object_ids: list[str] | tuple[str, ...]) -> AgentStates:
        """The states without the agents ``object_ids`` (each must exist)."""
        drop = {self.index(o) for o in object_ids}
        return self.take([r for r in range(self.num_agents) if r not in drop])

    def with_agent(self, object_id: str, category: str, source: str, *, xy: np.ndarray, heading: np.ndarray,
                   speed: np.ndarray, valid: np.ndarray, size: np.ndarray | tuple[float, float, float],
                   z: np.ndarray | None = None, node_id: int = -1) -> AgentStates:
        """The states with one agent added (``xy [T, 2]``, ``heading / speed / valid [T]``, ``size [3]``,
        ``z [T]`` default half the box height above ground), or replaced when ``object_id`` exists."""
        size = np.asarray(size, dtype=np.float64).reshape(3)
        z = np.full(self.num_steps, size[2] / 2.0) if z is None else np.asarray(z, dtype=np.float64)
        row: dict[str, Any] = dict(xy=np.asarray(xy, np.float64)[None], z=z[None],
                                   heading=np.asarray(heading, np.float64)[None],
                                   speed=np.asarray(speed, np.float64)[None], valid=np.asarray(valid, bool)[None],
                                   size=size[None])
        if object_id in self.object_ids:
            k = self.index(object_id)
            arrays: dict[str, Any] = {
                name: np.concatenate([getattr(self, name)[:k], value, getattr(self, name)[k + 1:]])
                for name, value in row.items()}
            return replace(self, categories=self.categories[:k] + (category,) + self.categories[k + 1:],
                           sources=self.sources[:k] + (source,) + self.sources[k + 1:],
                           node_ids=np.concatenate([self.node_ids[:k], [node_id], self.node_ids[k + 1:]]), **arrays)
        arrays = {name: np.concatenate([getattr(self, name), value]) for name, value in row.items()}
        return replace(self, object_ids=self.object_ids + (object_id,), categories=self.categories + (category,),
                       sources=self.sources + (source,), node_ids=np.concatenate([self.node_ids, [node_id]]),
                       **arrays)

    @classmethod
    def from_log(cls, log: SceneLog, node_of_object: dict[str, int] | None = None) -> AgentStates:
        """Every track of ``log`` plus the ego, on the log's frames (absent frames invalid).

        ``node_of_object`` maps object ids to scene-graph node ids (others get ``-1``).
        """
        n_frames = len(log.timestamps_us)
        frame_idx = np.arange(n_frames, dtype=np.int64)
        times = (np.asarray(log.timestamps_us, np.int64) - int(log.timestamps_us[0])) / 1e6
        categories = {o.object_id: o.category for o in log.objects}
        node_of_object = node_of_object or {}
        tracks = [t for t in log.tracks if len(t) > 0]
        a = len(tracks) + 1
        xy = np.zeros((a, n_frames, 2))
        z = np.zeros((a, n_frames))
        heading = np.zeros((a, n_frames))
        speed = np.zeros((a, n_frames))
        size = np.zeros((a, 3))
        valid = np.zeros((a, n_frames), dtype=bool)
        ego_xy = log.ego_poses[:, :2, 3]
        xy[0], z[0] = ego_xy, log.ego_poses[:, 2, 3] + EGO_SIZE[2] / 2.0
        heading[0] = np.unwrap([yaw_of_rotation(p[:3, :3]) for p in log.ego_poses])
        step = np.diff(ego_xy, axis=0)
        dt = np.maximum(np.diff(times), 1e-6)
        ego_speed = np.linalg.norm(step, axis=1) / dt
        speed[0] = np.concatenate([ego_speed[:1], ego_speed]) if n_frames > 1 else 0.0
        size[0], valid[0] = EGO_SIZE, True
        for k, track in enumerate(tracks, start=1):
            rows = np.asarray(track.frame_idx, np.int64)
            keep = (rows >= 0) & (rows < n_frames)
            rows = rows[keep]
            xy[k, rows] = track.center[keep, :2]
            z[k, rows] = track.center[keep, 2]
            heading[k, rows] = track.heading[keep]
            speed[k, rows] = track.speed[keep]
            size[k] = np.median(track.size[keep], axis=0) if keep.any() else track.size[0]
            valid[k, rows] = True
        ids = (EGO_ID, *(t.object_id for t in tracks))
        return cls(object_ids=ids, categories=("vehicle", *(categories.get(t.object_id, "other") for t in tracks)),
                   sources=("log",) * a,
                   node_ids=np.array([-1, *(node_of_object.get(t.object_id, -1) for t in tracks)], dtype=np.int64),
                   frame_idx=frame_idx, times=times, xy=xy, z=z, heading=heading, speed=speed, size=size,
                   valid=valid)
