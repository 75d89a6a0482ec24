"""A stored log, unedited or edited, as ``ExportScenario`` windows.

``export_log_scenarios`` takes a log, the agent states to export (the log's own, :func:`log_agent_states`, or an
edit's) and which agents the scenario is about, and returns one ``ExportScenario`` per window of the layout
(``export.windows``). Per track:

* the ego is the SDC; its box is the log's ``metadata["ego_size"]`` when given (its pose is the bottom of the box,
  as the loaders store it, so the box centre is half its height above the pose);
* velocities are the signed speed along the heading (the log model keeps speed, not velocity vectors);
* ids come from ``export.ids`` (the source's integers where it has them); the object id -> track id mapping is in
  ``ExportScenario.source_object_ids``;
* removed agents are absent because they are not in the states; agents never valid in a window are left out of it.

Scenario ids are ``<key>-w<window>`` (``key``: sequence, edit and attempt), deterministic and file-name safe.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from simsplat_core.export.ids import SDC_TRACK_ID_KEY, track_ids
from simsplat_core.export.map_features import ExportMap, export_map, log_signals
from simsplat_core.export.record import STATE_COLUMNS, ExportScenario
from simsplat_core.export.windows import ExportLayout, Window, plan_windows, sample_states
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.types import SceneLog

#: Log category -> exported agent type (others: ``"other"``).
AGENT_TYPE_OF_CATEGORY: dict[str, str] = {"vehicle": "vehicle", "pedestrian": "pedestrian", "cyclist": "cyclist"}
#: Sources of the agents a scenario is about (its objects of interest) and of those to predict.
INTEREST_SOURCES: frozenset[str] = frozenset({"edited", "inserted"})
PREDICT_SOURCES: frozenset[str] = frozenset({"edited", "inserted", "refined"})


@dataclass(frozen=True, eq=False)
class ScenarioSource:
    """What to export of one log.

    Attributes:
        log: the stored log (map, metadata, object ids; images not needed).
        states: the agents to export, ego included (``log_agent_states(log)`` or an edit's states).
        key: file-name-safe key of the scenario (sequence, edit, attempt): scenario ids are ``<key>-w<k>``.
        interest: object ids of the agents the scenario is about.
        predict: object ids of the agents to predict (those not valid at a window's current step are skipped).
        metadata: facts written with every window (run, edit, prompt, category, ...).
    """

    log: SceneLog
    states: AgentStates
    key: str
    interest: tuple[str, ...] = ()
    predict: tuple[str, ...] = ()
    metadata: Mapping[str, str] = field(default_factory=dict)


def _json_list(log: SceneLog, key: str) -> list[str]:
    raw = log.metadata.get(key)
    if not raw:
        return []
    value = json.loads(raw)
    return [str(v) for v in (value if isinstance(value, list) else [value])]


def log_agent_states(log: SceneLog) -> AgentStates:
    """The log's own agents (``AgentStates.from_log``) with the ego's box from ``metadata["ego_size"]``."""
    states = AgentStates.from_log(log)
    raw = log.metadata.get("ego_size")
    if not raw:
        return states
    size = np.asarray(json.loads(raw), np.float64).reshape(3)
    ego = states.index(EGO_ID)
    sizes = states.size.copy()
    sizes[ego] = size
    z = states.z.copy()
    z[ego] = log.ego_poses[:, 2, 3] + size[2] / 2.0
    return replace(states, size=sizes, z=z)


def log_source(log: SceneLog) -> ScenarioSource:
    """The unedited log as a scenario source: its objects of interest and tracks to predict from the source's
    metadata (Waymo's ``objects_of_interest`` / ``tracks_to_predict``, Argoverse 2's focal and scored tracks)."""
    interest = _json_list(log, "objects_of_interest") or _json_list(log, "focal_track_id")
    predict = _json_list(log, "tracks_to_predict") or (_json_list(log, "focal_track_id")
                                                      + _json_list(log, "scored_track_ids"))
    return ScenarioSource(log, log_agent_states(log), key=f"{log.seq_id}-log", interest=tuple(interest),
                          predict=tuple(dict.fromkeys(predict)))


def edit_source(log: SceneLog, states: AgentStates, key: str, metadata: Mapping[str, str]) -> ScenarioSource:
    """An edit of ``log`` as a scenario source: its edited and inserted agents are the objects of interest, those
    and the agents the refinement moved are to predict."""
    interest = tuple(o for o, s in zip(states.object_ids, states.sources) if s in INTEREST_SOURCES)
    predict = tuple(o for o, s in zip(states.object_ids, states.sources) if s in PREDICT_SOURCES)
    return ScenarioSource(log, states, key, interest, predict, metadata)


def box_sizes(log: SceneLog, states: AgentStates) -> np.ndarray:
    """``[A, T, 3]`` box sizes per agent and step: the log's per-frame boxes for agents the states keep from the
    log (source ``"log"`` or ``"refined"``: the same object), the states' one size elsewhere."""
    sizes = np.broadcast_to(states.size[:, None, :], (states.num_agents, states.num_steps, 3)).copy()
    rows = {o: k for k, (o, src) in enumerate(zip(states.object_ids, states.sources)) if src in ("log", "refined")}
    for track in log.tracks:
        k = rows.get(track.object_id)
        if k is None:
            continue
        frames = np.asarray(track.frame_idx, np.int64)
        keep = (frames >= 0) & (frames < states.num_steps)
        sizes[k, frames[keep]] = track.size[keep]
    return sizes


def _state_grid(states: AgentStates, sizes: np.ndarray, window: Window) -> tuple[np.ndarray, np.ndarray]:
    """``[A, S, 9]`` box states and ``[A, S]`` validity of every agent at the window's steps (``sizes``
    ``[A, T, 3]`` per log frame, taken at the nearest frame)."""
    sampled = sample_states(states, window.source)
    a, s = sampled.valid.shape
    grid = np.zeros((a, s, len(STATE_COLUMNS)))
    grid[..., 0:2] = sampled.xy
    grid[..., 2] = sampled.z
    nearest = np.clip(np.round(np.nan_to_num(window.source)).astype(np.int64), 0, states.num_steps - 1)
    grid[..., 3:6] = sizes[:, nearest]
    grid[..., 6] = sampled.heading
    grid[..., 7] = sampled.speed * np.cos(sampled.heading)
    grid[..., 8] = sampled.speed * np.sin(sampled.heading)
    grid[~sampled.valid] = 0.0
    return grid, sampled.valid


def _window_signals(source_signals: tuple, window: Window) -> tuple:
    if not source_signals:
        return ()
    out = []
    for pos in window.source:
        out.append(() if np.isnan(pos) else source_signals[int(round(pos))])
    return tuple(out)


def export_log_scenarios(src: ScenarioSource, layout: ExportLayout | None = None,
                         exported_map: ExportMap | None = None) -> list[ExportScenario]:
    """One ``ExportScenario`` per window of ``src`` (module docstring). ``exported_map``: the log's map when the
    caller already built it (several edits of one log)."""
    layout = layout or ExportLayout()
    log, states = src.log, src.states
    exported_map = exported_map or export_map(log)
    signals = log_signals(log, exported_map.ids)
    plan = plan_windows(states.times, layout)
    log_ids = [o.object_id for o in log.objects]
    added = [o for o in states.object_ids if o not in set(log_ids) and o != EGO_ID]
    ids = track_ids(log_ids, EGO_ID, added, log.metadata.get(SDC_TRACK_ID_KEY))
    agent_types = [AGENT_TYPE_OF_CATEGORY.get(c, "other") for c in states.categories]
    notes = "; ".join(plan.notes + exported_map.notes)
    sizes = box_sizes(log, states)
    out = []
    for window in plan.windows:
        grid, valid = _state_grid(states, sizes, window)
        keep = np.flatnonzero(valid.any(axis=1) | (np.asarray(states.object_ids) == EGO_ID))
        object_ids = [states.object_ids[r] for r in keep]
        rows = {o: k for k, o in enumerate(object_ids)}
        current = layout.current_index
        predict = tuple(rows[o] for o in src.predict if o in rows and valid[keep[rows[o]], current])
        interest = tuple(ids.of(o) for o in src.interest if o in rows)
        metadata = {
            "seq_id": log.seq_id, "log_source": log.source, "window": str(window.index),
            "window_start_s": f"{window.times[0]:.6f}", "dt_s": f"{1.0 / layout.hz:.6f}",
            "track_ids_from_source": str(ids.from_source).lower(), "notes": notes, **src.metadata,
        }
        out.append(ExportScenario(
            scenario_id=f"{src.key}-w{window.index}",
            timestamps_s=window.times,
            current_time_index=current,
            track_ids=np.array([ids.of(o) for o in object_ids], np.int64),
            agent_types=tuple(agent_types[r] for r in keep),
            states=grid[keep],
            valid=valid[keep],
            sdc_index=rows[EGO_ID],
            objects_of_interest=interest,
            tracks_to_predict=predict,
            track_sources=tuple(states.sources[r] for r in keep),
            source_object_ids=tuple(object_ids),
            map_features=exported_map.features,
            signals=_window_signals(signals, window),
            metadata=metadata,
        ))
    return out


def export_unedited(logs: Sequence[SceneLog], layout: ExportLayout | None = None) -> list[ExportScenario]:
    """Every window of every log, unedited."""
    return [s for log in logs for s in export_log_scenarios(log_source(log), layout)]
