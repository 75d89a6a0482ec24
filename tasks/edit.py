"""Edit one stored scene from a prompt (or a command file) and store the edit (what ``simsplat edit`` runs).

Thin: load the stored sequence (log without images, scene graph, language scene, asset bank), call
``simsplat_core.editing`` (parse, ground, apply, validate), render every frame and camera of the edited graph,
and write the edit with ``storage.edits``: ``edits/<run_id>/<seq_id>/<edit_id>/`` plus one row of the run's
``edits`` table. A refused or failed edit writes only its failure record.

``edit_id`` is a content key of (sequence, stored scene, language scene, asset bank, prompt, commands, editor
options, this module's version): the same edit of the same inputs is found again and not re-rendered.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pydantic

from simsplat_core.editing.apply import apply_edit
from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.commands import EditProgram, program_from_json
from simsplat_core.editing.delta import apply_delta
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.ops import node_factory
from simsplat_core.editing.options import DEFAULT_OPTIONS, EditorOptions
from simsplat_core.editing.parse.prompt import parse_prompt
from simsplat_core.editing.renders import FrameRender, frame_views, render_frame, render_frames
from simsplat_core.editing.result import EditedScene, EditRefused
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import default_text_encoder
from simsplat_core.motion.predictor import MotionPredictor
from simsplat_core.scene import SceneGraph
from simsplat_core.types import SceneLog
from simsplat_core.viz.before_after import FramePair, before_after_picture, pick_views, sample_steps
from simsplat_core.viz.bev import edit_bev
from simsplat_core.viz.bev_animation import bev_animation_frames, bev_fps
from simsplat_core.viz.images import to_uint8
from storage import ArtifactStore, content_key, read_scene, read_scene_log
from storage.assets import read_asset_bank
from storage.edits import (
    DeltaBase,
    EditRecord,
    command_json,
    edit_dir,
    read_edit_delta,
    read_edit_manifest,
    record_failure,
    staged_edit,
)
from storage.language_scenes import read_language_scene
from storage.runs import new_run_id

logger = logging.getLogger(__name__)

#: Version of the edit stage; part of every edit id.
EDIT_VERSION = "edit-v2"
#: Frames shown in ``before_after.png``.
BEFORE_AFTER_FRAMES = 4
#: Run id of edits made without ``--run-id``.
DEFAULT_RUN_ID = "manual"

#: ``progress(done, total)`` after each rendered frame.
Progress = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class LoadedEdit:
    """A stored sequence ready to edit: the context and where its parts came from."""

    ctx: EditContext
    scene_hash: str
    language_hash: str
    bank_hash: str
    seconds: float


@dataclass(frozen=True, eq=False)
class EditRun:
    """What one edit attempt did.

    Attributes:
        status: ``"succeeded"``, ``"refused"`` or ``"failed"``.
        run_id, seq_id, edit_id, edit_uri: where it is stored (``edit_uri`` is ``""`` when nothing but the
            failure record was written).
        prompt, program: the words and the commands (``None`` when the prompt did not parse / the JSON was bad).
        edited: the edited scene (``None`` unless it succeeded).
        reason, message: why it was refused / failed (``""`` otherwise).
        seconds: per stage (``load``, ``parse``, ``apply``, ``render``, ``write``, ``total``).
        bytes: bytes per part of the stored edit (``total`` included; empty when nothing was written).
        skipped: the same edit was already stored (nothing re-rendered).
    """

    status: str
    run_id: str
    seq_id: str
    edit_id: str
    edit_uri: str
    prompt: str
    program: EditProgram | None
    edited: EditedScene | None
    reason: str = ""
    message: str = ""
    seconds: dict[str, float] = field(default_factory=dict)
    bytes: dict[str, int] = field(default_factory=dict)
    skipped: bool = False


def load_edit_context(store: ArtifactStore, seq_id: str, *, engine: QueryEngine | None = None,
                      bank: AssetBank | None = None, bank_hash: str | None = None,
                      predictor: MotionPredictor | None = None) -> LoadedEdit:
    """The :class:`EditContext` of the newest language scene of ``seq_id`` (its stored scene graph, the log
    without images) and the newest asset bank of the store (``None`` when it has none: inserts and
    replacements are then refused, naming ``simsplat assets build``). ``predictor`` drives refinement
    (default: the reactive traffic model).

    Raises:
        FileNotFoundError: no complete log / language scene of ``seq_id`` (naming what to run).
    """
    started = time.perf_counter()
    log = read_scene_log(store, seq_id, load_images=False)
    loaded = read_language_scene(store, seq_id, with_records=False)
    scene_hash = str(loaded.manifest.get("scene_hash", ""))
    if not scene_hash:
        raise FileNotFoundError(f"{store.uri(loaded.relpath)}: the language scene of {seq_id!r} has no reconstructed "
                                "scene (a log without camera images cannot be edited: nothing to render)")
    graph = SceneGraph.from_records(read_scene(store, seq_id, scene_hash).records)
    if bank is None:
        try:
            bank = read_asset_bank(store)
        except FileNotFoundError as exc:
            logger.warning("%s; inserts and replacements will be refused", exc)
    engine = engine or QueryEngine(default_text_encoder())
    ctx = EditContext.create(log, graph, loaded.scene, engine, bank, predictor)
    return LoadedEdit(ctx, scene_hash, loaded.language_hash, bank.bank_hash if bank is not None else "",
                      time.perf_counter() - started)


def rebuild_edit(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> SceneGraph:
    """The edited graph of a stored edit, rebuilt from its delta, the stored scene and the asset bank it names
    (``apply_delta``: the same function the editor used).

    Raises:
        FileNotFoundError: the edit, its scene or its asset bank is not in the store.
        ValueError: the delta does not apply to the stored scene.
    """
    stored = read_edit_delta(store, run_id, seq_id, edit_id)
    base = stored.base
    graph = SceneGraph.from_records(read_scene(store, base.seq_id, base.scene_hash).records)
    if tuple(int(f) for f in graph.frame_indices) != base.frame_indices:
        raise ValueError(f"edit {edit_id}: scene {base.scene_hash[:12]} has other frames than the edit was made on")
    bank = read_asset_bank(store, base.bank_hash) if stored.delta.added else None
    return apply_delta(graph, stored.delta, node_factory(bank.get if bank is not None else _no_asset,
                                                         graph.frame_indices))


def _no_asset(asset_id: str) -> Asset:
    raise KeyError(f"no asset bank to build {asset_id!r} from")


def edit_key(loaded: LoadedEdit, prompt: str, program: EditProgram | None, options: EditorOptions,
             raw_commands: str = "") -> str:
    """Content key of an edit (module docstring)."""
    predictor = loaded.ctx.motion_predictor().name if options.refinement != "none" else ""
    return content_key("edit", EDIT_VERSION, loaded.ctx.log.seq_id, loaded.scene_hash, loaded.language_hash,
                       loaded.bank_hash, prompt, command_json(program), raw_commands, options, predictor)


def _failure(store: ArtifactStore, loaded: LoadedEdit, run_id: str, edit_id: str, prompt: str,
             program: EditProgram | None, status: str, reason: str, message: str, seconds: dict[str, float]
             ) -> EditRun:
    record = EditRecord(run_id=run_id, seq_id=loaded.ctx.log.seq_id, edit_id=edit_id, prompt=prompt,
                        command_json=command_json(program), status=status, failure_reason=f"{reason}: {message}")
    record_failure(store, record, program)
    logger.info("%s %s: %s (%s)", loaded.ctx.log.seq_id, status, message, reason)
    return EditRun(status, run_id, loaded.ctx.log.seq_id, edit_id, "", prompt, program, None, reason, message,
                   seconds)


def run_edit(store_root: str, seq_id: str, prompt: str = "", *, commands_json: str | None = None,
             commands_source: str = "command JSON", run_id: str | None = None,
             options: EditorOptions = DEFAULT_OPTIONS, loaded: LoadedEdit | None = None,
             progress: Progress | None = None) -> EditRun:
    """Edit ``seq_id`` by ``prompt`` (or by the commands in ``commands_json``) and store the result.

    Returns an :class:`EditRun` for every outcome the user caused (refusals, bad command JSON); only
    unexpected errors raise, after their failure record is written.

    Raises:
        FileNotFoundError: the store lacks the sequence's log or language scene.
    """
    store = ArtifactStore(store_root)
    run_id = run_id or DEFAULT_RUN_ID
    seconds: dict[str, float] = {}
    loaded = loaded or load_edit_context(store, seq_id)
    seconds["load"] = loaded.seconds
    started = time.perf_counter() - loaded.seconds  # the totals include loading
    ctx = loaded.ctx

    t = time.perf_counter()
    program: EditProgram | None = None
    try:
        if commands_json is not None:
            program = program_from_json(commands_json, source=commands_source)
            if prompt and not program.prompt:
                program = program.model_copy(update={"prompt": prompt})
            prompt = prompt or program.prompt
        else:
            program = parse_prompt(prompt, encoder=ctx.engine.text_encoder)
            program = program if program.prompt else program.model_copy(update={"prompt": prompt})
    except (pydantic.ValidationError, json.JSONDecodeError) as exc:
        seconds["parse"] = time.perf_counter() - t
        edit_id = edit_key(loaded, prompt, None, options, commands_json or "")[:16]
        return _failure(store, loaded, run_id, edit_id, prompt, None, "refused", "invalid_command",
                        schema_error_message(exc, commands_source), seconds)
    except EditRefused as exc:
        seconds["parse"] = time.perf_counter() - t
        edit_id = edit_key(loaded, prompt, None, options)[:16]
        return _failure(store, loaded, run_id, edit_id, prompt, None, "refused", exc.reason, str(exc), seconds)
    seconds["parse"] = time.perf_counter() - t
    key = edit_key(loaded, prompt, program, options)
    edit_id = key[:16]

    t = time.perf_counter()
    try:
        edited = apply_edit(ctx, program, options)
    except EditRefused as exc:
        seconds["apply"] = time.perf_counter() - t
        message = str(exc) if exc.command_index is None else f"command {exc.command_index + 1}: {exc}"
        return _failure(store, loaded, run_id, edit_id, prompt, program, "refused", exc.reason, message, seconds)
    seconds["apply"] = time.perf_counter() - t

    rel = edit_dir(run_id, seq_id, edit_id)
    manifest = read_edit_manifest(store, run_id, seq_id, edit_id)
    if manifest is not None and manifest.get("key") == key:
        seconds["total"] = time.perf_counter() - started
        logger.info("%s: edit %s already stored, skipping", seq_id, edit_id)
        return EditRun("succeeded", run_id, seq_id, edit_id, store.uri(rel), prompt, program, edited, seconds=seconds,
                       bytes=dict(manifest.get("bytes", {})), skipped=True)
    record = EditRecord(run_id=run_id, seq_id=seq_id, edit_id=edit_id, prompt=prompt,
                        command_json=command_json(program), status="succeeded")
    try:
        sizes = write_edit(store, record, key, loaded, program, edited, seconds, progress)
    except Exception as exc:
        _failure(store, loaded, run_id, edit_id, prompt, program, "failed", "error", f"{type(exc).__name__}: {exc}",
                 seconds)
        raise
    seconds["total"] = time.perf_counter() - started
    return EditRun("succeeded", run_id, seq_id, edit_id, store.uri(rel), prompt, program, edited, seconds=seconds,
                   bytes=sizes)


def schema_error_message(exc: Exception, source: str) -> str:
    """A one-line message naming each bad field of a command file (pydantic) or where the JSON broke."""
    if isinstance(exc, json.JSONDecodeError):
        return f"{source}: not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno})"
    assert isinstance(exc, pydantic.ValidationError)
    parts = []
    for err in exc.errors():
        where = ".".join(str(p) for p in err["loc"]) or "(top level)"
        parts.append(f"{where}: {err['msg']}")
    return f"{source}: {len(parts)} schema error(s): " + "; ".join(parts)


def _changed_nodes(edited: EditedScene) -> tuple[np.ndarray, np.ndarray]:
    """Node ids to outline: in the original (removed, replaced, re-tracked) and in the edit (added, re-tracked)."""
    delta = edited.delta
    before = sorted(set(delta.removed_node_ids) | set(delta.retracked))
    after = sorted({a.node_id for a in delta.added} | set(delta.retracked))
    return np.asarray(before, np.int32), np.asarray(after, np.int32)


def _original_pixels(language: LanguageScene, frames: list[int], cameras: tuple[str, ...], nodes: np.ndarray
                     ) -> np.ndarray:
    """``[F, C]`` pixels of ``nodes`` in the stored scene's node-id maps (zeros where it has none)."""
    out = np.zeros((len(frames), len(cameras)), np.int64)
    maps = language.node_id_maps
    if maps is None or not language.maps_valid or not len(nodes):
        return out
    rows = {int(f): k for k, f in enumerate(language.frame_indices)}
    cols = {c: k for k, c in enumerate(language.cameras)}
    for i, f in enumerate(frames):
        for j, c in enumerate(cameras):
            if f in rows and c in cols:
                out[i, j] = int(np.isin(maps[rows[f], cols[c]], nodes).sum())
    return out


@dataclass
class _Shown:
    """What the before/after picture needs of the edited renders: per frame the uint8 images and the edited
    objects' pixels (kept for every frame: which ones show the edit is known only at the end)."""

    frames: list[int] = field(default_factory=list)
    cameras: tuple[str, ...] = ()
    images: list[list[np.ndarray]] = field(default_factory=list)
    masks: list[list[np.ndarray]] = field(default_factory=list)

    def add(self, frame: FrameRender, nodes: np.ndarray) -> None:
        assert frame.node_id is not None
        self.frames.append(frame.frame_idx)
        self.cameras = frame.cameras
        self.images.append([to_uint8(np.clip(rgb, 0.0, 1.0)) for rgb in frame.rgb])
        self.masks.append([np.isin(ids, nodes) for ids in frame.node_id])

    def pixels(self) -> np.ndarray:
        return np.array([[int(m.sum()) for m in row] for row in self.masks], np.int64).reshape(len(self.frames), -1)


def _before_after(log: SceneLog, edited: EditedScene, language: LanguageScene, shown: _Shown, title: str,
                  active: np.ndarray) -> np.ndarray:
    """Original over edited at up to :data:`BEFORE_AFTER_FRAMES` frames that show the edit (the original rendered
    here, at those frames only)."""
    before_nodes, _ = _changed_nodes(edited)
    pixels = shown.pixels() + _original_pixels(language, shown.frames, shown.cameras, before_nodes)
    views = pick_views(pixels, BEFORE_AFTER_FRAMES)
    if not views:  # nothing visible: the frames where the edited agents exist, first camera
        steps = sample_steps(active, BEFORE_AFTER_FRAMES)
        wanted = {int(edited.states.frame_idx[s]) for s in steps}
        views = [(row, 0) for row, f in enumerate(shown.frames) if f in wanted]
    pairs = []
    for row, cam in views:
        frame_idx = shown.frames[row]
        before = render_frame(edited.original, frame_idx, frame_views(log, frame_idx))
        assert before.node_id is not None
        k = before.cameras.index(shown.cameras[cam])
        t = float(edited.states.times[int(np.searchsorted(edited.states.frame_idx, frame_idx))])
        pairs.append(FramePair(f"t={t:.1f}s {shown.cameras[cam]}", before.rgb[k], shown.images[row][cam],
                               np.isin(before.node_id[k], before_nodes), shown.masks[row][cam]))
    return before_after_picture(pairs, title=title)


def write_edit(store: ArtifactStore, record: EditRecord, key: str, loaded: LoadedEdit, program: EditProgram,
               edited: EditedScene, seconds: dict[str, float], progress: Progress | None = None, *,
               append: bool = True) -> dict[str, int]:
    """Render and write the edit directory atomically (``storage.edits.staged_edit``; ``append``: also append
    ``record`` to the edits table); returns bytes per part. Adds ``render`` (rasterizing, edited and original) and
    ``write`` (encoding, pictures, files) to ``seconds``."""
    ctx = loaded.ctx
    log = ctx.log
    frames = sorted({img.frame_idx for img in log.images})
    before, after = edited.original_states, edited.states
    active = np.zeros(after.num_steps, bool)
    for r, source in enumerate(after.sources):
        if source in ("edited", "inserted"):
            active |= after.valid[r]
    for oid in set(before.object_ids) - set(after.object_ids):
        active |= before.valid[before.index(oid)]
    _, after_nodes = _changed_nodes(edited)
    info = {"scene_hash": loaded.scene_hash, "language_hash": loaded.language_hash, "bank_hash": loaded.bank_hash,
            "prompt": record.prompt}
    render_s = 0.0
    t = time.perf_counter()
    with staged_edit(store, record, key, info, append=append) as writer:
        writer.command(program)
        writer.trajectories(record.edit_id, after)
        writer.delta(edited.delta, DeltaBase(log.seq_id, loaded.scene_hash, loaded.bank_hash,
                                             tuple(int(f) for f in ctx.graph.frame_indices)))
        shown = _Shown()
        r0 = time.perf_counter()
        for frame in render_frames(edited.graph, log, frames, progress=progress,
                                   ego_poses=edited.ego_poses(log.ego_poses)):
            render_s += time.perf_counter() - r0
            assert frame.node_id is not None
            for c, camera in enumerate(frame.cameras):
                writer.render(camera, frame.frame_idx, frame.rgb[c], frame.alpha[c], frame.node_id[c])
            shown.add(frame, after_nodes)
            r0 = time.perf_counter()
        title = record.prompt or "; ".join(edited.summary_lines())
        writer.png("bev.png", edit_bev(log.map_features, before, after, title=title))
        writer.video("bev.mp4", bev_animation_frames(log.map_features, before, after, title=title), bev_fps(after))
        r0 = time.perf_counter()
        picture = _before_after(log, edited, ctx.language, shown, title, active)
        render_s += time.perf_counter() - r0
        writer.png("before_after.png", picture)
        writer.validation(edited.validation.as_dict())
        sizes = dict(writer.bytes)
    seconds["render"] = render_s
    seconds["write"] = time.perf_counter() - t - render_s
    sizes["total"] = sum(sizes.values())
    return sizes


def edit_as_dict(run: EditRun, graph: SceneGraph | None = None) -> dict[str, Any]:
    """The attempt as plain JSON-able data (``simsplat edit --json``): ``status``, ``seq_id``, ``run_id``,
    ``edit_id``, ``edit_dir``, ``prompt``, ``commands``, ``grounded`` (per command: target / anchor node and
    object ids), ``changes``, ``new_object_ids``, ``validation``, ``reason`` / ``message`` of a refusal,
    ``seconds`` and ``bytes``."""
    object_of = {n.node_id: n.object_id for n in graph.object_nodes} if graph is not None else {}
    out: dict[str, Any] = {
        "status": run.status, "seq_id": run.seq_id, "run_id": run.run_id, "edit_id": run.edit_id,
        "edit_dir": run.edit_uri or None, "prompt": run.prompt,
        "commands": [c.model_dump(mode="json") for c in run.program.commands] if run.program is not None else [],
        "grounded": [], "changes": [], "new_object_ids": [], "validation": None, "refinement": None,
        "reason": run.reason or None, "message": run.message or None,
        "seconds": {k: round(v, 3) for k, v in run.seconds.items()}, "bytes": run.bytes, "skipped": run.skipped,
    }
    if run.edited is not None:
        for k, o in enumerate(run.edited.outcomes):
            out["grounded"].append({
                "command": k, "op": o.command.op,
                "target_node_ids": list(o.target_node_ids),
                "target_object_ids": [object_of.get(n, "") for n in o.target_node_ids],
                "anchor_node_ids": list(o.anchor_node_ids),
                "anchor_object_ids": [object_of.get(n, "") for n in o.anchor_node_ids]})
            out["changes"].append(o.summary)
            out["new_object_ids"] += list(o.new_object_ids)
        out["validation"] = run.edited.validation.as_dict()
        reaction = run.edited.refinement
        out["refinement"] = None if reaction is None else {
            "mode": reaction.mode, "predictor": reaction.predictor, "start_step": reaction.start_step,
            "refined": list(reaction.refined_ids), "replayed": dict(sorted(reaction.replayed.items()))}
    return out


def new_edit_run_id() -> str:
    """A fresh run id for a batch of edits (``edit-<UTC time>``)."""
    return new_run_id("edit")
