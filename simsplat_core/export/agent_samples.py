"""One agent-centric training sample from a dataset scenario (numpy): its history, future, neighbours and map.

Everything is in the **agent frame** at the current step: origin the agent's box centre, +x along its heading,
+y to its left, z up (metres, radians, m/s). ``origin`` (world x, y, z, heading) maps it back
(``torch_dataset.agent_to_world``).

A sample (``H`` history steps ending at the current step, ``Fu`` future steps after it, ``N`` <= ``max_neighbors``
neighbours, ``M`` <= ``max_polylines`` map polylines of ``P`` points):

==================  ===================  ==================================================================
key                 shape, dtype         meaning
==================  ===================  ==================================================================
history             [H, 10] float32      :data:`HISTORY_FEATURES` per step; zeros where invalid
history_valid       [H] bool             the agent exists at that step (false before the log starts)
future              [Fu, 5] float32      :data:`FUTURE_FEATURES` per step; zeros where invalid
future_valid        [Fu] bool            the agent exists at that step (false past the scenario's end)
agent_type          [] int64             index into ``record.AGENT_TYPES``
edit_flags          [6] float32          :data:`EDIT_FLAGS` (1.0 / 0.0)
neighbors           [N, H, 10] float32   the nearest other agents valid at the current step within
                                         ``map_radius_m``, nearest first; ``HISTORY_FEATURES`` in this frame
neighbors_valid     [N, H] bool
neighbor_type       [N] int64            index into ``record.AGENT_TYPES``
neighbor_track_id   [N] int64
map_polylines       [M, P, 12] float32   :data:`MAP_POINT_FEATURES`: the part of each of the nearest features
                                         within ``map_radius_m`` around the nearest point, resampled to P
                                         points evenly along its length, nearest feature first
map_valid           [M, P] bool          false for the repeats of a one-point feature (stop sign)
map_kind            [M] int64            index into ``record.MAP_FEATURE_KINDS``
map_feature_id      [M] int64
map_signal_state    [M] int64            index into ``record.SIGNAL_STATES`` at the current step; -1: none
origin              [4] float64          the agent's world x, y, z (metres) and heading (radians)
track_id            [] int64
scenario_id         str
==================  ===================  ==================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.export.dataset_arrays import ScenarioArrays
from simsplat_core.export.map_polylines import local_polylines
from simsplat_core.export.record import (
    HEADING,
    HEIGHT,
    LENGTH,
    MAP_FEATURE_KINDS,
    TRACK_SOURCES,
    VX,
    VY,
    WIDTH,
    X,
    Y,
    Z,
)
from simsplat_core.geometry import wrap_angle

#: Per-step features of ``history`` and ``neighbors`` (agent frame).
HISTORY_FEATURES: tuple[str, ...] = (
    "x", "y", "cos_heading", "sin_heading", "velocity_x", "velocity_y", "length", "width", "height", "z",
)
#: Per-step features of ``future`` (agent frame; heading relative to the agent's current heading, in (-pi, pi]).
FUTURE_FEATURES: tuple[str, ...] = ("x", "y", "heading", "velocity_x", "velocity_y")
#: Per-point features of ``map_polylines``: position, unit direction to the next point (the last point repeats
#: its predecessor's; zero for one point) and the feature kind one-hot.
MAP_POINT_FEATURES: tuple[str, ...] = ("x", "y", "z", "dir_x", "dir_y") + tuple(f"kind_{k}" for k in MAP_FEATURE_KINDS)
#: ``edit_flags`` entries: the agent's track source is edited / inserted / refined, it is an object of interest, it
#: is a track to predict, the scenario comes from an edit.
EDIT_FLAGS: tuple[str, ...] = ("edited", "inserted", "refined", "of_interest", "to_predict", "scenario_edited")


@dataclass(frozen=True)
class SampleConfig:
    """How much of a scenario one sample holds.

    Attributes:
        history_steps: ``H``, steps up to and including the current one.
        future_steps: ``Fu``, steps after the current one.
        map_radius_m: map points and neighbours farther than this from the agent (metres, in the ground plane)
            are left out.
        max_polylines: at most this many map features, nearest first.
        points_per_polyline: ``P``.
        max_neighbors: at most this many other agents, nearest first.
    """

    history_steps: int = 11
    future_steps: int = 80
    map_radius_m: float = 50.0
    max_polylines: int = 64
    points_per_polyline: int = 20
    max_neighbors: int = 32

    def __post_init__(self) -> None:
        for name in ("history_steps", "points_per_polyline"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be at least 1, got {getattr(self, name)}")
        for name in ("future_steps", "max_polylines", "max_neighbors"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must not be negative, got {getattr(self, name)}")
        if not self.map_radius_m > 0:
            raise ValueError(f"map_radius_m must be positive, got {self.map_radius_m}")


# ----------------------------------------------------------------------------- frames
def to_agent_frame(points: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """World ``[..., 2 or 3]`` points -> the frame of ``origin`` (x, y, z, heading): translated, rotated by -heading."""
    c, s = np.cos(origin[3]), np.sin(origin[3])
    dx, dy = points[..., 0] - origin[0], points[..., 1] - origin[1]
    out = np.empty(points.shape, np.float64)
    out[..., 0] = c * dx + s * dy
    out[..., 1] = -s * dx + c * dy
    if points.shape[-1] > 2:
        out[..., 2] = points[..., 2] - origin[2]
    return out


def _rotate(vectors: np.ndarray, heading: float) -> np.ndarray:
    """World ``[..., 2]`` vectors (velocities) -> the axes of a frame turned by ``heading``."""
    return to_agent_frame(vectors.astype(np.float64), np.array([0.0, 0.0, 0.0, heading]))


def _step_features(states: np.ndarray, valid: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """``[..., 9]`` world box states -> ``[..., 10]`` :data:`HISTORY_FEATURES`, zeros where not ``valid``."""
    local = to_agent_frame(states[..., [X, Y, Z]].astype(np.float64), origin)
    heading = states[..., HEADING] - origin[3]
    velocity = _rotate(states[..., [VX, VY]], origin[3])
    out = np.stack([local[..., 0], local[..., 1], np.cos(heading), np.sin(heading), velocity[..., 0],
                    velocity[..., 1], states[..., LENGTH], states[..., WIDTH], states[..., HEIGHT], local[..., 2]], -1)
    return np.where(valid[..., None], out, 0.0).astype(np.float32)


def _window(scene: ScenarioArrays, rows: np.ndarray, start: int, length: int) -> tuple[np.ndarray, np.ndarray]:
    """``[R, length, 9]`` states and ``[R, length]`` validity of track ``rows`` at steps ``start ..``; steps outside
    the scenario are invalid."""
    steps = np.arange(start, start + length)
    inside = (steps >= 0) & (steps < scene.num_steps)
    clipped = steps.clip(0, scene.num_steps - 1)
    return scene.states[rows[:, None], clipped], scene.valid[rows[:, None], clipped] & inside


# ----------------------------------------------------------------------------- the map
def _directions(points: np.ndarray) -> np.ndarray:
    """``[M, P, 3]`` -> ``[M, P, 2]`` unit ground-plane direction to the next point (the last repeats its
    predecessor's; zero for one point or a zero-length step)."""
    if points.shape[1] < 2:
        return np.zeros((*points.shape[:2], 2))
    delta = np.diff(points[..., :2], axis=1)
    delta = np.concatenate([delta, delta[:, -1:]], axis=1)
    norm = np.linalg.norm(delta, axis=-1, keepdims=True)
    return np.divide(delta, norm, out=np.zeros_like(delta), where=norm > 1e-9)


def map_polylines(scene: ScenarioArrays, origin: np.ndarray, config: SampleConfig) -> dict[str, np.ndarray]:
    """The ``map_*`` entries of a sample (module docstring) around ``origin``."""
    local = to_agent_frame(scene.map_points.astype(np.float64), origin)  # [Q, 3]
    near = local_polylines(local, scene.map_point_feature, len(scene.feature_ids), config.map_radius_m,
                           config.max_polylines, config.points_per_polyline, tie_break=scene.feature_ids)
    kinds = scene.feature_kinds[near.features].astype(np.int64)
    one_hot = np.eye(len(MAP_FEATURE_KINDS))[kinds]  # [M, K]
    polylines = np.concatenate([near.points, _directions(near.points),
                                np.broadcast_to(one_hot[:, None], (len(kinds), config.points_per_polyline,
                                                                   len(MAP_FEATURE_KINDS)))], axis=-1)
    return {"map_polylines": polylines.astype(np.float32), "map_valid": near.valid, "map_kind": kinds,
            "map_feature_id": scene.feature_ids[near.features].astype(np.int64),
            "map_signal_state": scene.signal_states[scene.current_time_index, near.features].astype(np.int64)}


# ----------------------------------------------------------------------------- one sample
def agent_origin(scene: ScenarioArrays, row: int) -> np.ndarray:
    """``[4]`` float64 world x, y, z and heading of track ``row`` at the current step."""
    state = scene.states[row, scene.current_time_index].astype(np.float64)
    return np.array([state[X], state[Y], state[Z], state[HEADING]])


def _neighbors(scene: ScenarioArrays, row: int, origin: np.ndarray, config: SampleConfig) -> dict[str, np.ndarray]:
    """The ``neighbor*`` entries: other tracks valid now within ``map_radius_m``, nearest (then lowest id) first."""
    now = scene.current_time_index
    valid_now = scene.valid[:, now].copy()
    valid_now[row] = False
    local_now = to_agent_frame(scene.states[:, now, :2].astype(np.float64), origin)
    distance = np.hypot(local_now[:, 0], local_now[:, 1])
    others = np.flatnonzero(valid_now & (distance <= config.map_radius_m))
    others = others[np.lexsort([scene.track_ids[others], distance[others]])][:config.max_neighbors]
    states, valid = _window(scene, others, now - config.history_steps + 1, config.history_steps)
    return {"neighbors": _step_features(states, valid, origin), "neighbors_valid": valid,
            "neighbor_type": scene.agent_types[others].astype(np.int64),
            "neighbor_track_id": scene.track_ids[others].astype(np.int64)}


def _edit_flags(scene: ScenarioArrays, row: int) -> np.ndarray:
    """``[6]`` :data:`EDIT_FLAGS` of track ``row``."""
    source = TRACK_SOURCES[int(scene.sources[row])]
    flags = [source == "edited", source == "inserted", source == "refined", bool(scene.of_interest[row]),
             bool(scene.to_predict[row]), scene.edited]
    return np.array(flags, np.float32)


def agent_sample(scene: ScenarioArrays, row: int, config: SampleConfig) -> dict[str, np.ndarray | str]:
    """The sample of track ``row`` (valid at the current step) of ``scene`` (module docstring)."""
    now = scene.current_time_index
    if not scene.valid[row, now]:
        raise ValueError(f"scenario {scene.scenario_id!r}: track {int(scene.track_ids[row])} is not valid at the "
                         f"current step {now}")
    origin = agent_origin(scene, row)
    own = np.array([row])
    history, history_valid = _window(scene, own, now - config.history_steps + 1, config.history_steps)
    future_states, future_valid = _window(scene, own, now + 1, config.future_steps)
    ahead, ahead_valid = future_states[0], future_valid[0]
    future = np.concatenate([to_agent_frame(ahead[:, [X, Y]].astype(np.float64), origin),
                             wrap_angle(ahead[:, [HEADING]] - origin[3]), _rotate(ahead[:, [VX, VY]], origin[3])],
                            axis=1)
    return {
        "history": _step_features(history[0], history_valid[0], origin),
        "history_valid": history_valid[0],
        "future": np.where(ahead_valid[:, None], future, 0.0).astype(np.float32),
        "future_valid": ahead_valid,
        "agent_type": np.int64(scene.agent_types[row]),
        "edit_flags": _edit_flags(scene, row),
        **_neighbors(scene, row, origin, config),
        **map_polylines(scene, origin, config),
        "origin": origin,
        "track_id": np.int64(scene.track_ids[row]),
        "scenario_id": scene.scenario_id,
    }
