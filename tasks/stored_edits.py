"""What ``simsplat edit``, mining and the editing benchmarks share about edits in the store: a stored sequence's
edit context (log without images, scene graph, language scene, asset bank), the content key of an edit, writing an
edit directory (every frame and camera rendered, the pictures) and rebuilding a stored edit from its delta.

``edit_key`` is a content key of (sequence, stored scene, language scene, asset bank, prompt, commands, editor
options, :data:`EDIT_VERSION`): the same edit of the same inputs is found again and not re-rendered.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.commands import EditProgram
from simsplat_core.editing.delta import apply_delta
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.ops import node_factory
from simsplat_core.editing.options import EditorOptions
from simsplat_core.editing.renders import render_frames
from simsplat_core.editing.result import EditedScene
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import default_text_encoder
from simsplat_core.motion.predictor import MotionPredictor
from simsplat_core.scene import SceneGraph
from simsplat_core.viz.bev import edit_bev
from simsplat_core.viz.bev_animation import bev_animation_frames, bev_fps
from simsplat_core.viz.edit_pictures import ShownFrames, active_steps, changed_nodes, edit_before_after
from storage import ArtifactStore, content_key, read_scene, read_scene_log
from storage.assets import read_asset_bank
from storage.edits import DeltaBase, EditRecord, command_json, read_edit_delta, staged_edit
from storage.inventory import LANGUAGE_SCENE, require_sequences
from storage.language_scenes import read_language_scene

logger = logging.getLogger(__name__)

#: Version of the edit stage; part of every edit id.
EDIT_VERSION = "edit-v2"

#: ``progress(done, total)`` after each rendered frame.
Progress = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class LoadedEdit:
    """A stored sequence ready to edit: the context, the store it was read from and where its parts came from."""

    store: ArtifactStore
    ctx: EditContext
    scene_hash: str
    language_hash: str
    bank_hash: str
    seconds: float


def load_edit_context(store: ArtifactStore | str, seq_id: str, *, engine: QueryEngine | None = None,
                      bank: AssetBank | None = None, bank_hash: str | None = None,
                      predictor: MotionPredictor | None = None) -> LoadedEdit:
    """The :class:`EditContext` of the newest language scene of ``seq_id`` (its stored scene graph, the log
    without images) and the newest asset bank of the store (``None`` when it has none: inserts and
    replacements are then refused, naming ``simsplat assets build``). ``store``: the store, or its root (opened
    here, once: the returned ``LoadedEdit.store``). ``predictor`` drives refinement (default: the reactive traffic
    model).

    Raises:
        MissingInputError: no complete log / language scene of ``seq_id`` (naming what to run).
        FileNotFoundError: the language scene has no reconstructed scene.
    """
    started = time.perf_counter()
    store = store if isinstance(store, ArtifactStore) else ArtifactStore(store)
    require_sequences(store, [seq_id], LANGUAGE_SCENE)
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
    return LoadedEdit(store, ctx, scene_hash, loaded.language_hash, bank.bank_hash if bank is not None else "",
                      time.perf_counter() - started)


def edit_key(loaded: LoadedEdit, prompt: str, program: EditProgram | None, options: EditorOptions,
             raw_commands: str = "") -> str:
    """Content key of an edit (module docstring)."""
    predictor = loaded.ctx.motion_predictor().name if options.refinement != "none" else ""
    return content_key("edit", EDIT_VERSION, loaded.ctx.log.seq_id, loaded.scene_hash, loaded.language_hash,
                       loaded.bank_hash, prompt, command_json(program), raw_commands, options, predictor)


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
    active = active_steps(edited)
    _, after_nodes = changed_nodes(edited)
    info = {"scene_hash": loaded.scene_hash, "language_hash": loaded.language_hash, "bank_hash": loaded.bank_hash,
            "prompt": record.prompt}
    render_s = 0.0
    t = time.perf_counter()
    with staged_edit(store, record, key, info, append=append) as writer:
        writer.command(program)
        writer.trajectories(record.edit_id, after)
        writer.delta(edited.delta, DeltaBase(log.seq_id, loaded.scene_hash, loaded.bank_hash,
                                             tuple(int(f) for f in ctx.graph.frame_indices)))
        shown = ShownFrames()
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
        picture = edit_before_after(log, edited, ctx.language, shown, title, active)
        render_s += time.perf_counter() - r0
        writer.png("before_after.png", picture)
        writer.validation(edited.validation.as_dict())
        sizes = dict(writer.bytes)
    seconds["render"] = render_s
    seconds["write"] = time.perf_counter() - t - render_s
    sizes["total"] = sum(sizes.values())
    return sizes


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
