"""A stored scenario (one edit of a run) as a Rerun recording (``.rrd``), to open in the Rerun viewer.

    data = scenario_recording(store, run_id, seq_id, edit_id)          # the .rrd bytes
    summary = write_scenario_recording(store_root, run_id, seq_id, edit_id, "scenario.rrd")

What the recording holds (entity paths; timelines ``frame`` (the log's frame index) and ``time`` (seconds since
the log's first frame)):

    world                       right-handed, z up, metres (the log's world frame)
    world/map/<kind>            the road map's polylines and polygons (static)
    world/paths/log             every agent's logged path (static, grey)
    world/paths/scenario        every agent's path after the edit, coloured by source (static)
    world/agents                every agent's 3D box at each frame, coloured by source, labelled by object id
    world/cameras/<camera>      each camera's pose and intrinsics at each frame, with the edit's render
    scenario                    the prompt and the validation verdict (static text)

Colours by source: log grey, edited orange, inserted green, refined blue. Needs the optional ``rerun-sdk``
package (``pip install 'simsplat[rerun]'``); without it :class:`RerunUnavailableError` says so.
"""

from __future__ import annotations

import importlib.util
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.types import SceneLog
from storage.edits import (
    edit_dir,
    read_edit_manifest,
    read_edit_program,
    read_trajectories,
    render_relpath,
    trajectory_states,
    validation_from_json,
)
from storage.errors import MissingInputError
from storage.logs import read_scene_log
from storage.store import ArtifactStore, join_relpath
from tasks.dashboard.files import exr_preview

logger = logging.getLogger(__name__)

#: RGB colour of an agent's box and path, by ``AgentStates.sources``.
SOURCE_COLORS: dict[str, tuple[int, int, int]] = {
    "log": (150, 150, 150), "edited": (230, 120, 20), "inserted": (40, 170, 80), "refined": (40, 110, 220)}
#: RGB colour of each map kind's lines.
MAP_COLORS: dict[str, tuple[int, int, int]] = {
    "lane": (120, 120, 160), "road_edge": (60, 60, 60), "crosswalk": (220, 220, 220), "drivable_area": (90, 90, 90),
    "sidewalk": (170, 150, 120), "lane_marking": (230, 210, 90)}
#: Map kinds drawn as closed polygons.
POLYGON_KINDS: frozenset[str] = frozenset({"crosswalk", "drivable_area", "sidewalk"})


class RerunUnavailableError(RuntimeError):
    """The optional ``rerun-sdk`` package is not installed."""


@dataclass(frozen=True)
class RecordingSummary:
    """What a written recording holds: its path and size, frames, agents, cameras, images and entity paths."""

    path: str
    bytes: int
    frames: int
    agents: int
    cameras: tuple[str, ...]
    images: int
    entities: tuple[str, ...]


def rerun_available() -> bool:
    """Whether the optional rerun-sdk package is installed (without importing it)."""
    return importlib.util.find_spec("rerun") is not None


def _rerun() -> Any:
    try:
        import rerun
    except ImportError as exc:
        raise RerunUnavailableError("the Rerun export needs the rerun-sdk package: pip install 'simsplat[rerun]' "
                                    "(or pip install rerun-sdk)") from exc
    return rerun


def _require_edit(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> None:
    if read_edit_manifest(store, run_id, seq_id, edit_id) is None:
        raise MissingInputError(f"{store.uri(edit_dir(run_id, seq_id, edit_id))}: no complete edit stored there "
                                f"(run {run_id!r}, sequence {seq_id!r}, edit {edit_id!r})")


def _paths(states: AgentStates) -> list[np.ndarray]:
    """``[k, 3]`` path of each agent over its valid steps (box centres)."""
    return [np.column_stack([states.xy[a, states.valid[a]], states.z[a, states.valid[a]]])
            for a in range(states.num_agents)]


def _colors(states: AgentStates) -> np.ndarray:
    return np.asarray([SOURCE_COLORS.get(s, SOURCE_COLORS["log"]) for s in states.sources], np.uint8)


def _log_map(rr: Any, rec: Any, log: SceneLog) -> list[str]:
    entities = []
    for kind in sorted({f.kind for f in log.map_features}):
        strips = [np.vstack([f.points, f.points[:1]]) if kind in POLYGON_KINDS else f.points
                  for f in log.map_features if f.kind == kind and len(f.points) > 1]
        if strips:
            entity = f"world/map/{kind}"
            rec.log(entity, rr.LineStrips3D(strips, colors=MAP_COLORS.get(kind, (128, 128, 128)), radii=0.05),
                    static=True)
            entities.append(entity)
    return entities


def _log_paths(rr: Any, rec: Any, log_states: AgentStates, scenario: AgentStates) -> list[str]:
    rec.log("world/paths/log", rr.LineStrips3D(_paths(log_states), colors=SOURCE_COLORS["log"], radii=0.04,
                                               labels=list(log_states.object_ids)), static=True)
    rec.log("world/paths/scenario", rr.LineStrips3D(_paths(scenario), colors=_colors(scenario), radii=0.08,
                                                    labels=list(scenario.object_ids)), static=True)
    return ["world/paths/log", "world/paths/scenario"]


def _log_boxes(rr: Any, rec: Any, scenario: AgentStates, step: int) -> None:
    """Every agent valid at ``step`` as an oriented 3D box (yaw about z)."""
    rows = np.flatnonzero(scenario.valid[:, step])
    half_yaw = scenario.heading[rows, step] / 2.0
    quaternions = np.column_stack([np.zeros_like(half_yaw), np.zeros_like(half_yaw), np.sin(half_yaw),
                                   np.cos(half_yaw)])  # [n, 4] xyzw
    centers = np.column_stack([scenario.xy[rows, step], scenario.z[rows, step]])
    rec.log("world/agents", rr.Boxes3D(centers=centers, half_sizes=scenario.size[rows] / 2.0, quaternions=quaternions,
                                       colors=_colors(scenario)[rows],
                                       labels=[scenario.object_ids[r] for r in rows], show_labels=False))


def _render_cameras(store: ArtifactStore, rel: str) -> list[str]:
    renders = join_relpath(rel, "renders")
    return sorted(c for c in store.listdir(renders) if not c.startswith(".")) if store.is_dir(renders) else []


def _log_cameras(rr: Any, rec: Any, store: ArtifactStore, rel: str, log: SceneLog, frame_idx: int,
                 cameras: list[str]) -> int:
    """The cameras' poses, intrinsics and the edit's renders at ``frame_idx``; returns the images logged."""
    calibration = {(im.frame_idx, im.camera): im for im in log.images}
    images = 0
    for camera in cameras:
        entity = f"world/cameras/{camera}"
        calib = calibration.get((frame_idx, camera))
        if calib is not None:
            rec.log(entity, rr.Transform3D(translation=calib.cam_to_world[:3, 3], mat3x3=calib.cam_to_world[:3, :3]))
            rec.log(entity, rr.Pinhole(image_from_camera=calib.K, resolution=[calib.width, calib.height]))
        render = join_relpath(rel, render_relpath(camera, frame_idx))
        if store.exists(render):
            rec.log(entity, rr.EncodedImage(contents=exr_preview(store, render), media_type="image/png"))
            images += 1
    return images


def _describe(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> str:
    program = read_edit_program(store, run_id, seq_id, edit_id)
    try:
        validation = json.dumps(validation_from_json(store, run_id, seq_id, edit_id), indent=2, sort_keys=True)
    except FileNotFoundError:
        validation = "(no validation stored)"
    return (f"# {run_id} / {seq_id} / {edit_id}\n\n**Prompt:** {program.prompt}\n\n"
            f"## Validation\n\n```json\n{validation}\n```\n")


def record_scenario(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> tuple[bytes, RecordingSummary]:
    """The stored edit ``edit_id`` of ``seq_id`` in run ``run_id`` as ``.rrd`` bytes, with what it holds
    (``path`` empty). Raises :class:`RerunUnavailableError` without rerun-sdk and ``MissingInputError`` naming
    the edit directory when no complete edit is stored there."""
    rr = _rerun()
    _require_edit(store, run_id, seq_id, edit_id)
    rel = edit_dir(run_id, seq_id, edit_id)
    log = read_scene_log(store, seq_id, load_images=False)
    log_states = AgentStates.from_log(log)
    scenario = trajectory_states(read_trajectories(store, run_id, seq_id, edit_id), log_states)
    cameras = _render_cameras(store, rel)
    rec = rr.RecordingStream("simsplat", recording_id=f"{run_id}/{seq_id}/{edit_id}")
    memory = rec.memory_recording()
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("scenario", rr.TextDocument(_describe(store, run_id, seq_id, edit_id), media_type="text/markdown"),
            static=True)
    entities = ["world", "scenario", *_log_map(rr, rec, log), *_log_paths(rr, rec, log_states, scenario),
                "world/agents", *(f"world/cameras/{c}" for c in cameras)]
    images = 0
    for step, frame_idx in enumerate(scenario.frame_idx):
        rec.set_time("frame", sequence=int(frame_idx))
        rec.set_time("time", duration=float(scenario.times[step]))
        _log_boxes(rr, rec, scenario, step)
        images += _log_cameras(rr, rec, store, rel, log, int(frame_idx), cameras)
    rec.flush()
    data = bytes(memory.drain_as_bytes())
    logger.info("rerun recording of %s: %d frames, %d agents, %d images, %d bytes", rel, scenario.num_steps,
                scenario.num_agents, images, len(data))
    return data, RecordingSummary("", len(data), scenario.num_steps, scenario.num_agents, tuple(cameras), images,
                                  tuple(entities))


def scenario_recording(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> bytes:
    """The ``.rrd`` bytes of one stored scenario (:func:`record_scenario`)."""
    return record_scenario(store, run_id, seq_id, edit_id)[0]


def write_scenario_recording(store_root: str, run_id: str, seq_id: str, edit_id: str, out: str) -> RecordingSummary:
    """Write the recording of one stored scenario to ``out`` (atomically: a temporary name, then renamed)."""
    data, summary = record_scenario(ArtifactStore(store_root), run_id, seq_id, edit_id)
    target = Path(out).resolve()
    ArtifactStore(str(target.parent)).write_bytes(target.name, data)
    return RecordingSummary(str(target), summary.bytes, summary.frames, summary.agents, summary.cameras,
                            summary.images, summary.entities)


__all__ = ["RecordingSummary", "RerunUnavailableError", "record_scenario", "rerun_available", "scenario_recording",
           "write_scenario_recording"]
