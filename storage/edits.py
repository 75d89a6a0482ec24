"""Persist language edits: one directory per edit, one row per attempt in the run's ``edits`` table.

Layout (``DESIGN.md``)::

    edits/<run_id>/edits.parts/<part>.parquet    the edits table: one row per attempt, one immutable part per
                                                 append (``storage.table_parts``; edits.parquet of older stores
                                                 is still read)
    edits/<run_id>/<seq_id>/<edit_id>/           one staged directory: complete (with _SUCCESS.json) or absent
        command.json                             the EditProgram (with its schema_version)
        trajectories.parquet                     every agent at every valid step after the edit (no removed ones)
        delta/delta.json                         the edit on the stored scene: base scene (or the log, for a log
                                                 without images) and asset bank, removed node ids, added nodes
                                                 (asset references), re-tracked nodes
        delta/pose_tracks.parquet                the pose tracks of the added and re-tracked nodes
        renders/<camera>/<frame:06d>.exr         (logs with images) R, G, B, A (half floats, rounded to 1/256) +
                                                 id (float32 node id, -1 = nothing); zip, ~100 KB at 240 x 160
        bev.png, bev.mp4, before_after.png       pictures for people (no before_after.png without images)
        validation.json                          collisions / off-road / kinematics of the edited agents
        _SUCCESS.json                            key, byte counts per part

The delta holds no Gaussians: added nodes name ``(bank_hash, asset_id)``, so the edited graph is rebuilt
from the stored scene and the asset bank (``simsplat_core.editing.delta.apply_delta``).

A refused or failed attempt writes its row (``status`` ``"refused"`` / ``"failed"``, ``failure_reason``
``"<reason>: <message>"``) and, when a program was parsed and no complete edit of that id is stored,
``command.json`` + ``failure.json`` in the edit directory (no marker: readers of edits skip it). Nothing
stored before is changed.

Imports the editing core (torch) at the top: import this module only where edits are read or written
(it is not re-exported from ``storage``).
"""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa
import torch

from simsplat_core.editing.commands import EditProgram, program_from_json, program_to_json
from simsplat_core.editing.result import AddedNode, EditDelta
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scene.pose_track import Extrapolation, PoseTrack
from simsplat_core.viz.images import encode_png
from storage.errors import CorruptArtifactError
from storage.exr import render_channels, write_exr
from storage.markers import mark_done, read_marker
from storage.pictures import encode_mp4
from storage.schemas.base import arrow_to_vectors, vectors_to_arrow
from storage.schemas.edits import EDIT_POSE_TRACKS_SCHEMA, EDITS_MINING_COLUMNS, EDITS_SCHEMA, TRAJECTORIES_SCHEMA
from storage.store import ArtifactStore, join_relpath
from storage.table_parts import PARTS_SUFFIX, PartedTable

logger = logging.getLogger(__name__)

EDITS_DIR = "edits"
EDITS_TABLE_NAME = "edits"
DELTA_FORMAT = "simsplat.edit_delta"
DELTA_FORMAT_VERSION = 1
#: ``edits.status`` values.
EDIT_STATUSES: tuple[str, ...] = ("succeeded", "refused", "failed")


def _check_name(kind: str, value: str) -> str:
    if not value or "/" in value or value.startswith(".") or value != value.strip():
        raise ValueError(f"{kind} {value!r} must be a non-empty name without '/' or a leading '.'")
    return value


def edits_table_relpath(run_id: str) -> str:
    """``edits/<run_id>/edits.parts``: the folder of the run's edits table (``edits_table``)."""
    return join_relpath(EDITS_DIR, _check_name("run id", run_id), EDITS_TABLE_NAME + PARTS_SUFFIX)


def edit_dir(run_id: str, seq_id: str, edit_id: str) -> str:
    """``edits/<run_id>/<seq_id>/<edit_id>``."""
    return join_relpath(EDITS_DIR, _check_name("run id", run_id), _check_name("sequence id", seq_id),
                        _check_name("edit id", edit_id))


def render_relpath(camera: str, frame_idx: int) -> str:
    """``renders/<camera>/<frame:06d>.exr`` inside an edit directory."""
    return f"renders/{_check_name('camera', camera)}/{int(frame_idx):06d}.exr"


# ----------------------------------------------------------------------------- the edits table
@dataclass(frozen=True)
class EditRecord:
    """One row of the ``edits`` table.

    Attributes:
        attempt: 1 for the first attempt of ``edit_id`` in the run, then 2, 3, ... (``0`` before the row is
            appended: :func:`append_edit_record` numbers it).
        command_json: the program as JSON (``""`` when the prompt did not parse).
        status: one of :data:`EDIT_STATUSES`.
        failure_reason: ``"<reason>: <message>"`` (``""`` when it succeeded).
        mining: the mining columns of a mined attempt (``storage.schemas.EDITS_MINING_COLUMNS``: name -> value,
            ``export`` among them); empty for a plain edit (stored as nulls, ``export`` false).
    """

    run_id: str
    seq_id: str
    edit_id: str
    prompt: str
    command_json: str
    status: str
    failure_reason: str = ""
    attempt: int = 0
    mining: Mapping[str, Any] = dataclasses.field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        if self.status not in EDIT_STATUSES:
            raise ValueError(f"EditRecord.status must be one of {list(EDIT_STATUSES)}, got {self.status!r}")
        if (self.status == "succeeded") == bool(self.failure_reason):
            raise ValueError("EditRecord.failure_reason must be empty exactly when the status is 'succeeded'")
        unknown = sorted(set(self.mining) - set(EDITS_MINING_COLUMNS))
        if unknown:
            raise ValueError(f"EditRecord.mining: unknown column(s) {unknown}; known: {list(EDITS_MINING_COLUMNS)}")

    @property
    def export(self) -> bool:
        """Marked for export (an accepted mined scenario)."""
        return bool(self.mining.get("export"))


_RECORD_FIELDS = ("run_id", "seq_id", "edit_id", "attempt", "prompt", "command_json", "status", "failure_reason")


def _record_of(row: dict[str, Any]) -> EditRecord:
    mining = {k: row[k] for k in EDITS_MINING_COLUMNS if row.get(k) is not None}
    return EditRecord(**{k: row[k] for k in _RECORD_FIELDS}, mining=mining)


def _row_of(record: EditRecord) -> dict[str, Any]:
    mining = {k: record.mining.get(k) for k in EDITS_MINING_COLUMNS}
    mining["export"] = record.export
    return {**{k: getattr(record, k) for k in _RECORD_FIELDS}, **mining}


def edits_table(store: ArtifactStore, run_id: str) -> PartedTable:
    """The run's edits table: ``edits/<run_id>/edits.parts/`` (and ``edits.parquet`` of older stores)."""
    return PartedTable(store, join_relpath(EDITS_DIR, _check_name("run id", run_id)), EDITS_TABLE_NAME, EDITS_SCHEMA)


def edit_run_ids(store: ArtifactStore) -> list[str]:
    """The runs that have an edits table, sorted."""
    return [run for run in store.listdir(EDITS_DIR) if not run.startswith(".") and edits_table(store, run).exists()]


def read_edit_records(store: ArtifactStore, run_id: str) -> list[EditRecord]:
    """Every row of the run's edits table in append order (``[]`` when there is none). Version-1 tables (before the
    mining columns) read with empty ``mining``."""
    return [_record_of(row) for row in edits_table(store, run_id).read().to_pylist()]


def append_edit_records(store: ArtifactStore, records: Sequence[EditRecord]) -> list[EditRecord]:
    """Append ``records`` (all of one run) to the run's edits table as one new part; returns them numbered
    (``attempt``: 1 + the rows of the same sequence and edit id before).

    Appends never rewrite what is stored, so concurrent writers (Ray workers on several machines, an object store)
    cannot lose each other's rows. The numbering reads the table under the store's lock, which serialises the
    writers of one machine; one sequence's attempts come from one task, so their numbers never collide.
    """
    if not records:
        return []
    run_ids = {r.run_id for r in records}
    if len(run_ids) != 1:
        raise ValueError(f"append_edit_records: records of several runs {sorted(run_ids)}")
    table = edits_table(store, records[0].run_id)
    numbered: list[EditRecord] = []
    with store.exclusive(table.parts_relpath):
        rows = read_edit_records(store, records[0].run_id)
        for record in records:
            attempt = 1 + sum(r.edit_id == record.edit_id and r.seq_id == record.seq_id for r in rows + numbered)
            numbered.append(dataclasses.replace(record, attempt=attempt))
        table.append(pa.Table.from_pylist([_row_of(r) for r in numbered], schema=EDITS_SCHEMA))
    for record in numbered:
        logger.info("edits %s: %s %s attempt %d (%s)", record.run_id, record.seq_id, record.edit_id,
                    record.attempt, record.status)
    return numbered


def compact_edit_records(store: ArtifactStore, run_id: str) -> int:
    """Fold the run's edits parts into one (its single writer, once the run's tasks are done); returns how many
    parts were folded."""
    table = edits_table(store, run_id)
    if len(table.part_names()) < 2:
        return 0
    with store.exclusive(table.parts_relpath):
        return table.compact()


def append_edit_record(store: ArtifactStore, record: EditRecord) -> EditRecord:
    """Append ``record`` to its run's edits table (:func:`append_edit_records`); returns it numbered."""
    return append_edit_records(store, [record])[0]


def record_failure(store: ArtifactStore, record: EditRecord, program: EditProgram | None = None) -> EditRecord:
    """Store a refused / failed attempt: its row, and ``command.json`` + ``failure.json`` in the edit directory
    when a program was parsed and no complete edit of that id is stored (a stored edit is never touched)."""
    if record.status == "succeeded":
        raise ValueError("record_failure: the record's status is 'succeeded'")
    rel = edit_dir(record.run_id, record.seq_id, record.edit_id)
    if program is not None and read_marker(store, rel) is None:
        with store.staged_directory(rel) as tmp:
            store.write_bytes(join_relpath(tmp, "command.json"), program_to_json(program).encode("utf-8"))
            store.write_json(join_relpath(tmp, "failure.json"),
                             {"status": record.status, "failure_reason": record.failure_reason})
    return append_edit_record(store, record)


# ----------------------------------------------------------------------------- trajectories
def trajectories_table(edit_id: str, states: AgentStates) -> pa.Table:
    """DESIGN's ``trajectories`` table of ``states``: one row per (agent, valid step), agents in row order, with
    the box centre height ``z`` and the agent's box size (``length``, ``width``, ``height``, metres)."""
    rows, steps = np.nonzero(states.valid)  # row-major: agent by agent, steps increasing
    n = rows.size
    return pa.table({
        "edit_id": pa.array([edit_id] * n, pa.string()),
        "object_id": pa.array([states.object_ids[r] for r in rows], pa.string()),
        "category": pa.array([states.categories[r] for r in rows], pa.string()),
        "step": pa.array(states.frame_idx[steps].astype(np.int32), pa.int32()),
        "x": pa.array(states.xy[rows, steps, 0].astype(np.float32), pa.float32()),
        "y": pa.array(states.xy[rows, steps, 1].astype(np.float32), pa.float32()),
        "heading": pa.array(states.heading[rows, steps].astype(np.float32), pa.float32()),
        "speed": pa.array(states.speed[rows, steps].astype(np.float32), pa.float32()),
        "source": pa.array([states.sources[r] for r in rows], pa.string()),
        "z": pa.array(states.z[rows, steps].astype(np.float32), pa.float32()),
        "length": pa.array(states.size[rows, 0].astype(np.float32), pa.float32()),
        "width": pa.array(states.size[rows, 1].astype(np.float32), pa.float32()),
        "height": pa.array(states.size[rows, 2].astype(np.float32), pa.float32()),
    }, schema=TRAJECTORIES_SCHEMA)


def read_trajectories(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> pa.Table:
    """The ``trajectories`` table of a stored edit."""
    return store.read_table(join_relpath(edit_dir(run_id, seq_id, edit_id), "trajectories.parquet"),
                            TRAJECTORIES_SCHEMA)


#: Box (length, width, height) of an inserted agent of a ``trajectories`` table without sizes, per category.
_FALLBACK_SIZES: dict[str, tuple[float, float, float]] = {
    "vehicle": (4.8, 2.0, 1.6), "pedestrian": (0.6, 0.6, 1.75), "cyclist": (1.8, 0.6, 1.7),
}


def _optional_column(table: pa.Table, name: str) -> np.ndarray | None:
    """``[N]`` float64 values of a column added in a later version (NaN where null), ``None`` when absent."""
    if name not in table.column_names or table.column(name).null_count == len(table):
        return None
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False), np.float64)


def trajectory_states(table: pa.Table, log_states: AgentStates) -> AgentStates:
    """The agents of a stored edit's ``trajectories`` table as ``AgentStates`` on the log's frames.

    ``log_states``: the unedited log's agents (``AgentStates.from_log``), whose frames the steps index. Heights and
    boxes come from the table when it has them; a table without (written before those columns) takes them from the
    log for logged agents and, for inserted ones, a box of their category standing on the ego's ground height.
    """
    cols = {name: table.column(name).to_pylist() for name in ("object_id", "category", "source")}
    steps = np.asarray(table.column("step").to_numpy(), np.int64)
    ids, first, rows = np.unique(np.asarray(cols["object_id"], dtype=object), return_index=True, return_inverse=True)
    by_appearance = np.argsort(first)  # agents in the order the table lists them
    rows = np.argsort(by_appearance)[rows]
    first = first[by_appearance]
    order = [str(ids[k]) for k in by_appearance]
    a, t = len(order), log_states.num_steps
    if steps.size and (steps.min() < 0 or steps.max() >= t):
        raise ValueError(f"trajectories: step {int(steps.max())} is not a frame of the log ({t} frames)")
    categories = tuple(cols["category"][i] for i in first)
    sources = tuple(cols["source"][i] for i in first)
    xy, heading, speed = np.zeros((a, t, 2)), np.zeros((a, t)), np.zeros((a, t))
    valid = np.zeros((a, t), bool)
    xy[rows, steps, 0] = table.column("x").to_numpy()
    xy[rows, steps, 1] = table.column("y").to_numpy()
    heading[rows, steps] = table.column("heading").to_numpy()
    speed[rows, steps] = table.column("speed").to_numpy()
    valid[rows, steps] = True
    size, z = np.zeros((a, 3)), np.zeros((a, t))
    ego = log_states.index(EGO_ID)
    ground = log_states.z[ego] - log_states.size[ego, 2] / 2.0
    for k, (o, category) in enumerate(zip(order, categories)):
        if o in log_states.object_ids:
            j = log_states.index(o)
            size[k] = log_states.size[j]
            z[k] = np.where(log_states.valid[j], log_states.z[j], np.median(log_states.z[j][log_states.valid[j]]))
        else:
            size[k] = _FALLBACK_SIZES.get(category, (1.0, 1.0, 1.0))
            z[k] = ground + size[k, 2] / 2.0
    stored = {name: _optional_column(table, name) for name in ("z", "length", "width", "height")}
    if stored["z"] is not None:
        z[rows, steps] = np.where(np.isnan(stored["z"]), z[rows, steps], stored["z"])
    grouped = np.argsort(rows, kind="stable")
    bounds = np.searchsorted(rows[grouped], np.arange(1, a))
    for axis, name in enumerate(("length", "width", "height")):
        values = stored[name]
        if values is None:
            continue
        for k, mine in enumerate(np.split(values[grouped], bounds)):  # each agent's boxes, median of the known
            mine = mine[~np.isnan(mine)]
            if mine.size:
                size[k, axis] = float(np.median(mine))
    return AgentStates(object_ids=tuple(order), categories=categories, sources=sources,
                       node_ids=np.full(a, -1, np.int64), frame_idx=log_states.frame_idx, times=log_states.times,
                       xy=xy, z=z, heading=heading, speed=speed, size=size, valid=valid)


# ----------------------------------------------------------------------------- delta
@dataclass(frozen=True)
class DeltaBase:
    """What a delta applies to: the stored scene (or, for a log without images, the graph of the log's tracks)
    and the asset bank its added nodes come from.

    Attributes:
        seq_id, scene_hash: ``scenes/<seq_id>/<scene_hash>`` (``scene_hash`` ``""``: the base is the log).
        bank_hash: ``assets/<bank_hash>``, or the box-only bank's hash (``""`` when the edit added nothing).
        frame_indices: ``[F]`` the graph's frame axis (checked when rebuilding).
        log_key: the log's content key when the base is the log (``""`` otherwise).
    """

    seq_id: str
    scene_hash: str
    bank_hash: str
    frame_indices: tuple[int, ...]
    log_key: str = ""

    @property
    def from_log(self) -> bool:
        """Whether the delta applies to the log's tracks (no reconstructed scene)."""
        return not self.scene_hash


@dataclass(frozen=True, eq=False)
class StoredDelta:
    """A delta read back: the change and what it applies to."""

    delta: EditDelta
    base: DeltaBase


def _track_rows(node_id: int, track: PoseTrack, arc_length: np.ndarray | None) -> dict[str, Any]:
    n = len(track)
    arc = np.full(n, np.nan) if arc_length is None else np.asarray(arc_length, np.float64).reshape(n)
    return {"node_id": np.full(n, node_id, np.int32), "t": track.times.astype(np.float64),
            "transform": track.poses.detach().cpu().numpy().reshape(n, 16), "present": track.mask.cpu().numpy(),
            "arc_length": arc}


def _policy(track: PoseTrack) -> dict[str, str]:
    return {"before": track.before.value, "after": track.after.value}


def write_edit_delta(store: ArtifactStore, relpath: str, delta: EditDelta, base: DeltaBase) -> None:
    """Write ``delta/delta.json`` + ``delta/pose_tracks.parquet`` under ``relpath`` (an edit directory)."""
    parts = [_track_rows(a.node_id, a.track, a.arc_length) for a in delta.added]
    parts += [_track_rows(nid, track, None) for nid, track in sorted(delta.retracked.items())]
    columns = {k: np.concatenate([p[k] for p in parts]) if parts else np.zeros((0, 16) if k == "transform" else 0)
               for k in ("node_id", "t", "transform", "present", "arc_length")}
    table = pa.table({
        "node_id": pa.array(columns["node_id"].astype(np.int32), pa.int32()),
        "t": pa.array(columns["t"].astype(np.float64), pa.float64()),
        "transform": vectors_to_arrow(columns["transform"], 16),
        "present": pa.array(columns["present"].astype(bool), pa.bool_()),
        "arc_length": pa.array(columns["arc_length"].astype(np.float64), pa.float64()),
    })
    store.write_table(join_relpath(relpath, "delta", "pose_tracks.parquet"), table, EDIT_POSE_TRACKS_SCHEMA)
    body = {
        "format": DELTA_FORMAT, "version": DELTA_FORMAT_VERSION,
        "seq_id": base.seq_id, "scene_hash": base.scene_hash, "bank_hash": base.bank_hash,
        **({"base": "log", "log_key": base.log_key} if base.from_log else {}),
        "frame_indices": [int(f) for f in base.frame_indices],
        "removed_node_ids": [int(n) for n in delta.removed_node_ids],
        "added": [{"node_id": a.node_id, "object_id": a.object_id, "asset_id": a.asset_id, "category": a.category,
                   **_policy(a.track)} for a in delta.added],
        "retracked": [{"node_id": int(nid), **_policy(track)} for nid, track in sorted(delta.retracked.items())],
    }
    store.write_json(join_relpath(relpath, "delta", "delta.json"), body)


def read_edit_delta(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> StoredDelta:
    """The delta of a stored edit.

    Raises:
        FileNotFoundError: no such edit (naming the path).
        CorruptArtifactError, SchemaError: a file does not decode or a track is missing (naming the file).
    """
    rel = join_relpath(edit_dir(run_id, seq_id, edit_id), "delta")
    body = store.read_json(join_relpath(rel, "delta.json"))
    where = store.uri(join_relpath(rel, "delta.json"))
    if not isinstance(body, dict) or body.get("format") != DELTA_FORMAT:
        found = body.get("format") if isinstance(body, dict) else None
        raise CorruptArtifactError(f"{where}: not an edit delta (format {found!r}, expected {DELTA_FORMAT!r})")
    if int(body.get("version", 0)) > DELTA_FORMAT_VERSION:
        raise CorruptArtifactError(f"{where}: delta version {body['version']} is newer than supported "
                                   f"{DELTA_FORMAT_VERSION} (upgrade simsplat)")
    table = store.read_table(join_relpath(rel, "pose_tracks.parquet"), EDIT_POSE_TRACKS_SCHEMA)
    node_col = table.column("node_id").to_numpy()
    times, present = table.column("t").to_numpy(), table.column("present").to_numpy(zero_copy_only=False)
    transforms = arrow_to_vectors(table.column("transform")).reshape(-1, 4, 4)
    arcs = table.column("arc_length").to_numpy()

    def track_of(entry: dict[str, Any]) -> tuple[PoseTrack, np.ndarray]:
        rows = np.flatnonzero(node_col == int(entry["node_id"]))
        if rows.size == 0:
            raise CorruptArtifactError(f"{store.uri(join_relpath(rel, 'pose_tracks.parquet'))}: no track of node "
                                       f"{entry['node_id']}")
        rows = rows[np.argsort(times[rows], kind="stable")]
        track = PoseTrack(times[rows], torch.from_numpy(np.ascontiguousarray(transforms[rows])),
                          torch.from_numpy(present[rows].astype(bool)), Extrapolation(entry["before"]),
                          Extrapolation(entry["after"]))
        return track, arcs[rows]

    added = []
    for entry in body.get("added", []):
        track, arc = track_of(entry)
        added.append(AddedNode(node_id=int(entry["node_id"]), object_id=str(entry["object_id"]),
                               asset_id=str(entry["asset_id"]), category=str(entry["category"]), track=track,
                               arc_length=None if np.isnan(arc).all() else arc))
    retracked = {int(e["node_id"]): track_of(e)[0] for e in body.get("retracked", [])}
    delta = EditDelta(removed_node_ids=tuple(int(n) for n in body.get("removed_node_ids", [])), added=tuple(added),
                      retracked=retracked)
    base = DeltaBase(str(body["seq_id"]), str(body["scene_hash"]), str(body.get("bank_hash", "")),
                     tuple(int(f) for f in body.get("frame_indices", [])), str(body.get("log_key", "")))
    return StoredDelta(delta, base)


def read_edit_program(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> EditProgram:
    """``command.json`` of an edit (complete or failed) as a validated :class:`EditProgram`."""
    rel = join_relpath(edit_dir(run_id, seq_id, edit_id), "command.json")
    return program_from_json(store.read_bytes(rel), source=store.uri(rel))


# ----------------------------------------------------------------------------- writing one edit
#: Colour / alpha step of stored edit renders: 1/256 (error <= 0.002, half an 8-bit step: the precision of the
#: cameras' own 8-bit images; exact in half floats). The rasterizer's low bits are noise that zip cannot
#: compress: rounding them to 1/256 gives 80 KB instead of 118 KB per 240 x 160 view (-32 %).
RENDER_STEP = 1.0 / 256.0


def quantised(values: np.ndarray, step: float = RENDER_STEP) -> np.ndarray:
    """``values`` rounded to multiples of ``step`` (float32)."""
    return (np.round(np.asarray(values, np.float32) / step) * step).astype(np.float32)


class EditWriter:
    """Writes the files of one edit into its staged directory (see :func:`staged_edit`); counts bytes per part."""

    def __init__(self, store: ArtifactStore, relpath: str) -> None:
        self.store = store
        self.relpath = relpath
        self.bytes: dict[str, int] = {}
        self.renders = 0

    def _count(self, part: str, rel: str) -> None:
        self.bytes[part] = self.bytes.get(part, 0) + self.store.size(join_relpath(self.relpath, rel))

    def command(self, program: EditProgram) -> None:
        self.store.write_bytes(join_relpath(self.relpath, "command.json"), program_to_json(program).encode("utf-8"))
        self._count("command", "command.json")

    def trajectories(self, edit_id: str, states: AgentStates) -> None:
        self.store.write_table(join_relpath(self.relpath, "trajectories.parquet"), trajectories_table(edit_id, states),
                               TRAJECTORIES_SCHEMA)
        self._count("trajectories", "trajectories.parquet")

    def delta(self, delta: EditDelta, base: DeltaBase) -> None:
        write_edit_delta(self.store, self.relpath, delta, base)
        self._count("delta", "delta/delta.json")
        self._count("delta", "delta/pose_tracks.parquet")

    def render(self, camera: str, frame_idx: int, rgb: np.ndarray, alpha: np.ndarray, node_id: np.ndarray,
               depth: np.ndarray | None = None) -> None:
        """One camera's render (``rgb [H, W, 3]``, ``alpha [H, W]``, ``node_id [H, W]`` int, optional
        ``depth [H, W]``) as a half-float EXR (``id`` float32). Colours and alpha are first rounded to
        multiples of :data:`RENDER_STEP` (module docstring)."""
        rel = render_relpath(camera, frame_idx)
        channels = render_channels(rgb=quantised(rgb), alpha=quantised(alpha), depth=depth, node_id=node_id)
        write_exr(self.store, join_relpath(self.relpath, rel), channels, half=True)
        self._count("renders", rel)
        self.renders += 1

    def png(self, name: str, rgb: np.ndarray) -> None:
        if not name.endswith(".png") or "/" in name:
            raise ValueError(f"EditWriter.png: {name!r} must be a file name ending in .png")
        self.store.write_bytes(join_relpath(self.relpath, name), encode_png(rgb))
        self._count("pictures", name)

    def video(self, name: str, frames: list[np.ndarray], fps: float) -> None:
        """``[H, W, 3]`` uint8 RGB frames as an MP4 named ``name``."""
        if not name.endswith(".mp4") or "/" in name:
            raise ValueError(f"EditWriter.video: {name!r} must be a file name ending in .mp4")
        self.store.write_bytes(join_relpath(self.relpath, name), encode_mp4(frames, fps))
        self._count("pictures", name)

    def validation(self, report: dict[str, Any]) -> None:
        self.store.write_json(join_relpath(self.relpath, "validation.json"), report)
        self._count("validation", "validation.json")


@contextmanager
def staged_edit(store: ArtifactStore, record: EditRecord, key: str, info: dict[str, Any] | None = None, *,
                append: bool = True) -> Iterator[EditWriter]:
    """Write one edit atomically: yields an :class:`EditWriter` on a staged directory; when the block succeeds
    the directory (with ``_SUCCESS.json``: ``key``, byte counts, ``info``) replaces
    ``edits/<run>/<seq>/<edit>`` and ``record`` (status ``"succeeded"``) is appended to the edits table (unless
    ``append`` is false: the caller appends it, e.g. with the other attempts of a mining run). When the block
    raises nothing is written."""
    if record.status != "succeeded":
        raise ValueError(f"staged_edit: the record's status is {record.status!r}, not 'succeeded'")
    rel = edit_dir(record.run_id, record.seq_id, record.edit_id)
    with store.staged_directory(rel) as tmp:
        writer = EditWriter(store, tmp)
        yield writer
        sizes = dict(sorted(writer.bytes.items()))
        mark_done(store, tmp, key, {"run_id": record.run_id, "seq_id": record.seq_id, "edit_id": record.edit_id,
                                    "bytes": {**sizes, "total": sum(sizes.values())}, "renders": writer.renders,
                                    **dict(info or {})})
    if append:
        append_edit_record(store, record)


def read_edit_manifest(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> dict[str, Any] | None:
    """The ``_SUCCESS.json`` of a complete edit, or ``None``."""
    return read_marker(store, edit_dir(run_id, seq_id, edit_id))


def list_edits(store: ArtifactStore, run_id: str, seq_id: str) -> list[str]:
    """Edit ids of the complete edits of ``seq_id`` in the run, sorted."""
    base = join_relpath(EDITS_DIR, _check_name("run id", run_id), _check_name("sequence id", seq_id))
    return [e for e in store.listdir(base) if not e.startswith(".") and read_marker(store, join_relpath(base, e))]


def validation_from_json(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> dict[str, Any]:
    """``validation.json`` of a stored edit."""
    value = store.read_json(join_relpath(edit_dir(run_id, seq_id, edit_id), "validation.json"))
    if not isinstance(value, dict):
        raise CorruptArtifactError(f"{store.uri(edit_dir(run_id, seq_id, edit_id))}/validation.json: not an object")
    return value


def command_json(program: EditProgram | None) -> str:
    """The ``edits.command_json`` of ``program`` (compact; ``""`` for none)."""
    return "" if program is None else json.dumps(program.model_dump(mode="json"), sort_keys=True)
