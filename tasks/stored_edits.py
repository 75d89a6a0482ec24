"""What ``simsplat edit``, mining and the editing benchmarks share about edits in the store: a stored sequence's
edit context (log without images, scene graph, language scene, asset bank), the content key of an edit, writing an
edit directory (every frame and camera rendered, the pictures) and rebuilding a stored edit from its delta.

``edit_key`` is a content key of (sequence, stored scene, language scene, asset bank, prompt, commands, editor
options, :data:`EDIT_VERSION`): the same edit of the same inputs is found again and not re-rendered.

**Logs without camera images** (Waymo Open Motion and Argoverse 2 motion-forecasting scenarios) have no
reconstructed scene: their language scene was aligned from the tracks and map. They are edited on the graph of
their tracks (``simsplat_core.scene.track_graph``: the same node ids, no Gaussians) with box-only assets for
inserts (``simsplat_core.editing.assets.boxes``); the edit's key and delta name the log (its content key) in place
of a scene, and the edit directory has no renders and no ``before_after.png`` (nothing to render).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.boxes import box_asset_bank, is_box_bank
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
from simsplat_core.scene.track_graph import track_graph
from simsplat_core.viz.bev import edit_bev
from simsplat_core.viz.bev_animation import bev_animation_frames, bev_fps
from simsplat_core.viz.edit_pictures import ShownFrames, active_steps, changed_nodes, edit_before_after
from storage import ArtifactStore, content_key, read_scene, read_scene_log, require_log_manifest
from storage.assets import read_asset_bank
from storage.edits import DeltaBase, EditRecord, EditWriter, command_json, read_edit_delta, staged_edit
from storage.inventory import LANGUAGE_SCENE, require_sequences
from storage.language_scenes import read_language_scene

logger = logging.getLogger(__name__)

#: Version of the edit stage; part of every edit id.
EDIT_VERSION = "edit-v2"

#: ``progress(done, total)`` after each rendered frame.
Progress = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class LoadedEdit:
    """A stored sequence ready to edit: the context, the store it was read from and where its parts came from.

    Attributes:
        scene_hash: the reconstructed scene edited (``""``: a log without images, edited on its tracks).
        log_key: the log's content key (what the edit's key and delta name when there is no scene).
    """

    store: ArtifactStore
    ctx: EditContext
    scene_hash: str
    language_hash: str
    bank_hash: str
    seconds: float
    log_key: str = ""

    @property
    def renders(self) -> bool:
        """Whether the edit has a scene to render (a log without images has none)."""
        return bool(self.scene_hash)

    @property
    def base_key(self) -> str:
        """What the edit applies to: the scene hash, or ``log-<log key>`` for a log without images."""
        return self.scene_hash or f"log-{self.log_key}"


def load_edit_context(store: ArtifactStore | str, seq_id: str, *, engine: QueryEngine | None = None,
                      bank: AssetBank | None = None, bank_hash: str | None = None,
                      predictor: MotionPredictor | None = None) -> LoadedEdit:
    """The :class:`EditContext` of the newest language scene of ``seq_id`` (its stored scene graph, the log
    without images) and the newest asset bank of the store (``None`` when it has none: inserts and
    replacements are then refused, naming ``simsplat assets build``). A log without camera images is edited on
    the graph of its tracks with the box-only bank (module docstring; ``bank`` is then ignored). ``store``: the
    store, or its root (opened here, once: the returned ``LoadedEdit.store``). ``predictor`` drives refinement
    (default: the reactive traffic model).

    Raises:
        MissingInputError: no complete log / language scene of ``seq_id`` (naming what to run).
    """
    started = time.perf_counter()
    store = store if isinstance(store, ArtifactStore) else ArtifactStore(store)
    require_sequences(store, [seq_id], LANGUAGE_SCENE)
    log_key = str(require_log_manifest(store, seq_id, "to edit")["key"])
    log = read_scene_log(store, seq_id, load_images=False)
    loaded = read_language_scene(store, seq_id, with_records=False)
    scene_hash = str(loaded.manifest.get("scene_hash", ""))
    if scene_hash:
        graph = SceneGraph.from_records(read_scene(store, seq_id, scene_hash).records)
    else:
        logger.info("%s: no reconstructed scene (a log without images): editing its tracks, inserts as boxes", seq_id)
        graph, bank = track_graph(log), box_asset_bank()
    if bank is None:
        try:
            bank = read_asset_bank(store)
        except FileNotFoundError as exc:
            logger.warning("%s; inserts and replacements will be refused", exc)
    engine = engine or QueryEngine(default_text_encoder())
    ctx = EditContext.create(log, graph, loaded.scene, engine, bank, predictor)
    return LoadedEdit(store, ctx, scene_hash, loaded.language_hash, bank.bank_hash if bank is not None else "",
                      time.perf_counter() - started, log_key)


def edit_key(loaded: LoadedEdit, prompt: str, program: EditProgram | None, options: EditorOptions,
             raw_commands: str = "") -> str:
    """Content key of an edit (module docstring)."""
    predictor = loaded.ctx.motion_predictor().name if options.refinement != "none" else ""
    return content_key("edit", EDIT_VERSION, loaded.ctx.log.seq_id, loaded.base_key, loaded.language_hash,
                       loaded.bank_hash, prompt, command_json(program), raw_commands, options, predictor)


def write_edit(store: ArtifactStore, record: EditRecord, key: str, loaded: LoadedEdit, program: EditProgram,
               edited: EditedScene, seconds: dict[str, float], progress: Progress | None = None, *,
               append: bool = True) -> dict[str, int]:
    """Render and write the edit directory atomically (``storage.edits.staged_edit``; ``append``: also append
    ``record`` to the edits table); returns bytes per part. Adds ``render`` (rasterizing, edited and original) and
    ``write`` (encoding, pictures, files) to ``seconds``. A log without images gets no renders and no
    ``before_after.png`` (module docstring)."""
    ctx = loaded.ctx
    log = ctx.log
    before, after = edited.original_states, edited.states
    info = {"scene_hash": loaded.scene_hash, "language_hash": loaded.language_hash, "bank_hash": loaded.bank_hash,
            "prompt": record.prompt}
    if not loaded.renders:
        info["log_key"] = loaded.log_key
    render_s = 0.0
    t = time.perf_counter()
    with staged_edit(store, record, key, info, append=append) as writer:
        writer.command(program)
        writer.trajectories(record.edit_id, after)
        writer.delta(edited.delta, DeltaBase(log.seq_id, loaded.scene_hash, loaded.bank_hash,
                                             tuple(int(f) for f in ctx.graph.frame_indices), loaded.log_key))
        title = record.prompt or "; ".join(edited.summary_lines())
        if loaded.renders:
            render_s = _write_renders(writer, ctx, edited, title, progress)
        writer.png("bev.png", edit_bev(log.map_features, before, after, title=title))
        writer.video("bev.mp4", bev_animation_frames(log.map_features, before, after, title=title), bev_fps(after))
        writer.validation(edited.validation.as_dict())
        sizes = dict(writer.bytes)
    seconds["render"] = render_s
    seconds["write"] = time.perf_counter() - t - render_s
    sizes["total"] = sum(sizes.values())
    return sizes


def _write_renders(writer: EditWriter, ctx: EditContext, edited: EditedScene, title: str,
                   progress: Progress | None) -> float:
    """Every frame and camera of the edited scene rendered into ``writer``, and ``before_after.png``; returns the
    seconds spent rasterizing."""
    log = ctx.log
    frames = sorted({img.frame_idx for img in log.images})
    _, after_nodes = changed_nodes(edited)
    shown = ShownFrames()
    render_s = 0.0
    r0 = time.perf_counter()
    for frame in render_frames(edited.graph, log, frames, progress=progress,
                               ego_poses=edited.ego_poses(log.ego_poses)):
        render_s += time.perf_counter() - r0
        assert frame.node_id is not None
        for c, camera in enumerate(frame.cameras):
            writer.render(camera, frame.frame_idx, frame.rgb[c], frame.alpha[c], frame.node_id[c])
        shown.add(frame, after_nodes)
        r0 = time.perf_counter()
    r0 = time.perf_counter()
    picture = edit_before_after(log, edited, ctx.language, shown, title, active_steps(edited))
    render_s += time.perf_counter() - r0
    writer.png("before_after.png", picture)
    return render_s


def rebuild_edit(store: ArtifactStore, run_id: str, seq_id: str, edit_id: str) -> SceneGraph:
    """The edited graph of a stored edit, rebuilt from its delta, the stored scene and the asset bank it names
    (``apply_delta``: the same function the editor used). An edit of a log without images is rebuilt on the graph
    of the log's tracks with the box-only bank: a graph of poses without Gaussians.

    Raises:
        FileNotFoundError: the edit, its scene or its asset bank is not in the store.
        ValueError: the delta does not apply to the stored scene, or the log changed since the edit.
    """
    stored = read_edit_delta(store, run_id, seq_id, edit_id)
    base = stored.base
    if base.from_log:
        log_key = str(require_log_manifest(store, base.seq_id, "to rebuild the edit of")["key"])
        if log_key != base.log_key:
            raise ValueError(f"edit {edit_id}: made on log {base.seq_id!r} with key {base.log_key[:12]}, the store "
                             f"now holds key {log_key[:12]} (re-ingested since): edit it again")
        graph = track_graph(read_scene_log(store, base.seq_id, load_images=False))
        what = f"log {base.seq_id!r}"
    else:
        graph = SceneGraph.from_records(read_scene(store, base.seq_id, base.scene_hash).records)
        what = f"scene {base.scene_hash[:12]}"
    if tuple(int(f) for f in graph.frame_indices) != base.frame_indices:
        raise ValueError(f"edit {edit_id}: {what} has other frames than the edit was made on")
    bank: AssetBank | None = None
    if stored.delta.added:
        bank = box_asset_bank() if is_box_bank(base.bank_hash) else read_asset_bank(store, base.bank_hash)
    return apply_delta(graph, stored.delta, node_factory(bank.get if bank is not None else _no_asset,
                                                         graph.frame_indices))


def _no_asset(asset_id: str) -> Asset:
    raise KeyError(f"no asset bank to build {asset_id!r} from")
