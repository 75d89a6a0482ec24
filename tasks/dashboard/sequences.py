"""The sequence pages: every log of the store in one table, and one log's page (contact sheet, bird's-eye view,
reconstruction quality with ground truth next to a test render, the language scene's objects, a query box).

    listing = read_sequences(store)                                 # SequencesView: a row per log
    view = read_sequence(store, made, "synth-000000", q="the red car")   # SequenceView, or None: no such log

Every independently failing part is a ``Section``, so a corrupt artifact shows its message where it belongs. Logs
without camera images (Waymo motion, Argoverse 2 forecasting) have no contact sheet and no reconstruction; their
bird's-eye view, objects and query work as for the others. Nothing is written: pictures made on request (the
bird's-eye view, a test frame rendered when the scene stored none) go to ``made``.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from simsplat_core.scene_view import side_by_side
from simsplat_core.summary import LogSummary, summarize_log
from simsplat_core.types import SceneLog
from simsplat_core.viz.contact_sheet import bev_panel
from storage.artifact_ids import artifact_id
from storage.language_scenes import list_language_scenes
from storage.logs import list_logs, log_dir, read_log_manifest, read_scene_log
from storage.scenes import list_scenes, read_scene_manifest, scene_dir
from storage.schemas.runs import METRICS_SCHEMA
from storage.store import ArtifactStore, join_relpath
from tasks.answers import node_labels
from tasks.dashboard.files import MadePictures
from tasks.dashboard.sections import Section, section
from tasks.dashboard.sequence_query import QueryResult, answer_sequence_query, query_scene
from tasks.render import render_frame

T = TypeVar("T")

#: Frames shown on a contact sheet (evenly spread over the log).
CONTACT_FRAMES = 4
#: Test frames shown as ground truth next to their render.
COMPARED_FRAMES = 2
#: The reconstruction metrics shown, in order (``storage.scenes.METRIC_UNITS`` names them).
QUALITY_METRICS: tuple[str, ...] = ("psnr_test", "ssim_test", "psnr_test_dynamic", "ssim_test_dynamic", "psnr_train",
                                    "num_gaussians", "iterations", "wall_time_s")


@dataclass(frozen=True)
class SequenceRow:
    """One log of the store.

    Attributes:
        seq_id, source: the log and where it came from (``synthetic``, ``waymo``, ``av2``, ...).
        frames: time steps; cameras: camera names; images: stored camera images (0: a log without pixels).
        objects: tracked objects; scenes: complete reconstructions; aligned: it has a language scene.
    """

    seq_id: str
    source: str
    frames: int
    cameras: tuple[str, ...]
    images: int
    objects: int
    scenes: int
    aligned: bool

    @property
    def reconstructed(self) -> bool:
        return self.scenes > 0


@dataclass(frozen=True)
class SequencesView:
    """Attributes: store: its URI; rows: one section per log (a log whose manifest does not read shows why)."""

    store: str
    rows: Section[tuple[Section[SequenceRow], ...]]


@dataclass(frozen=True)
class CameraPicture:
    """One stored camera image: ``camera``, ``frame`` and its artifact id (``picture``: served as PNG)."""

    camera: str
    frame: int
    picture: str


@dataclass(frozen=True)
class ContactSheet:
    """The log's camera images at a few frames: ``frames`` shown, ``cameras`` in log order, ``rows``: one tuple of
    pictures per frame (a camera without pixels at that frame is left out)."""

    frames: tuple[int, ...]
    cameras: tuple[str, ...]
    rows: tuple[tuple[CameraPicture, ...], ...]


@dataclass(frozen=True)
class TestComparison:
    """A held-out frame: ``ground_truth`` (the log's image) next to ``render`` (the scene's), both picture ids;
    ``rendered_now``: the scene stored no render of it, so it was rendered for this page."""

    camera: str
    frame: int
    ground_truth: str
    render: str
    rendered_now: bool


@dataclass(frozen=True)
class ReconstructionQuality:
    """The newest reconstruction of a log.

    Attributes:
        scene_hash: its content key; scenes: how many complete reconstructions the log has.
        metrics: ``name -> value`` of :data:`QUALITY_METRICS` the scene stored (PSNR in dB, SSIM in [0, 1],
            wall time in s); units: ``name -> unit``.
        comparisons: held-out frames, ground truth next to the render.
    """

    scene_hash: str
    scenes: int
    metrics: dict[str, float]
    units: dict[str, str]
    comparisons: tuple[TestComparison, ...]


@dataclass(frozen=True)
class LanguageObject:
    """One object node of the language scene: its caption (``""`` without pixels), the aligner's motion class and
    the auto-labels of its motion and location (``""`` for static objects)."""

    node_id: int
    object_id: str
    category: str
    caption: str
    motion: str
    motion_label: str
    location: str


@dataclass(frozen=True)
class LanguageObjects:
    """The newest language scene of a log: its hashes and its object nodes."""

    model_hash: str
    language_hash: str
    objects: tuple[LanguageObject, ...]


@dataclass(frozen=True)
class LogFacts:
    """What the log holds: ``row`` (as in the list) and its ``summary`` (duration, objects per category, map
    features per kind, held-out frames; ``simsplat inspect`` prints the same)."""

    row: SequenceRow
    summary: LogSummary


@dataclass(frozen=True)
class SequenceView:
    """One log's page.

    Attributes:
        seq_id: the log; has_images: it has camera images (else no contact sheet and no reconstruction).
        facts, bev, objects: what the log holds, its bird's-eye view (a picture id), its language scene's objects
            (``None``: not aligned).
        contact_sheet, reconstruction: ``None`` for a log without images; the reconstruction's value is ``None``
            when the log is not reconstructed yet.
        query: the text asked (``""``: none), relevance: whether relevance maps were asked for, answer: the query's
            answer (``None`` when nothing was asked).
    """

    seq_id: str
    has_images: bool
    facts: Section[LogFacts]
    bev: Section[str]
    contact_sheet: Section[ContactSheet] | None
    reconstruction: Section[ReconstructionQuality | None] | None
    objects: Section[LanguageObjects | None]
    query: str
    relevance: bool
    answer: Section[QueryResult] | None


# ----------------------------------------------------------------------------- the list
def _row(store: ArtifactStore, seq_id: str) -> SequenceRow:
    manifest = read_log_manifest(store, seq_id)
    if manifest is None:
        raise FileNotFoundError(f"{store.uri(log_dir(seq_id))}: no complete log (its _SUCCESS.json went away)")
    tables = manifest.get("tables", {})
    return SequenceRow(seq_id=seq_id, source=str(manifest.get("source", "")),
                       frames=int(manifest.get("num_frames", 0)), cameras=tuple(manifest.get("cameras", [])),
                       images=int(manifest.get("images", {}).get("count", 0)),
                       objects=int(tables.get("objects", {}).get("rows", 0)),
                       scenes=len(list_scenes(store, seq_id)), aligned=bool(list_language_scenes(store, seq_id)))


def read_sequences(store: ArtifactStore) -> SequencesView:
    """Every complete log of ``store``, a row each."""
    def rows() -> tuple[Section[SequenceRow], ...]:
        return tuple(section(seq_id, functools.partial(_row, store, seq_id)) for seq_id in list_logs(store))
    return SequencesView(store.uri(), section("logs", rows))


# ----------------------------------------------------------------------------- one log
@functools.lru_cache(maxsize=8)
def _cached_log(store_root: str, seq_id: str, log_key: str) -> SceneLog:
    """The log without pixels, read once per content key (``log_key``: a rewritten log is read again)."""
    return read_scene_log(ArtifactStore(store_root), seq_id, load_images=False)


def read_log(store: ArtifactStore, seq_id: str) -> SceneLog:
    """``seq_id``'s log without pixels (cached per content key).

    Raises:
        FileNotFoundError: no complete log.
    """
    manifest = read_log_manifest(store, seq_id)
    if manifest is None:
        raise FileNotFoundError(f"{store.uri(log_dir(seq_id))}: no complete log")
    return _cached_log(store.root, seq_id, str(manifest.get("key", "")))


def _facts(store: ArtifactStore, seq_id: str, log: SceneLog) -> LogFacts:
    row = _row(store, seq_id)  # the summary counts loaded pixels: the log was read without them
    return LogFacts(row, dataclasses.replace(summarize_log(log), num_images=row.images))


def _with_log(name: str, log: Section[SceneLog], make: Callable[[SceneLog], T]) -> Section[T]:
    """``make(log)`` as a section; the log's own error when it did not read."""
    value = log.value
    return section(name, lambda: make(value)) if value is not None else Section(name, error=log.error)


def _image_relpath(seq_id: str, camera: str, frame: int) -> str:
    return join_relpath(log_dir(seq_id), "images", camera, f"{frame:06d}.exr")


def spread_frames(num_frames: int, count: int) -> tuple[int, ...]:
    """Up to ``count`` distinct frames evenly spread over ``[0, num_frames)``, first and last included."""
    if num_frames <= 0:
        return ()
    return tuple(sorted({int(round(f)) for f in np.linspace(0, num_frames - 1, min(count, num_frames))}))


def _contact_sheet(store: ArtifactStore, seq_id: str, log: SceneLog) -> ContactSheet:
    frames = spread_frames(log.num_frames, CONTACT_FRAMES)
    rows = []
    for frame in frames:
        rels = [(c, _image_relpath(seq_id, c, frame)) for c in log.cameras]
        rows.append(tuple(CameraPicture(c, frame, artifact_id(rel)) for c, rel in rels if store.exists(rel)))
    return ContactSheet(frames, tuple(log.cameras), tuple(rows))


@functools.lru_cache(maxsize=16)
def _rendered(store_root: str, seq_id: str, scene_hash: str, camera: str, frame: int) -> np.ndarray:
    """``[H, W, 3]`` float32: one camera of a scene rendered at ``frame`` (for scenes that stored no test render)."""
    images, _ = render_frame(ArtifactStore(store_root), seq_id, frame, cameras=[camera], scene_hash=scene_hash)
    return side_by_side(images)


def _comparisons(store: ArtifactStore, made: MadePictures, seq_id: str, scene_hash: str, log: SceneLog,
                 stored: set[str]) -> tuple[TestComparison, ...]:
    tests = sorted({img.frame_idx for img in log.images if img.split == "test"}) or [log.num_frames // 2]
    shown = [tests[i] for i in sorted(set(np.linspace(0, len(tests) - 1, min(COMPARED_FRAMES, len(tests)))
                                          .round().astype(int).tolist()))]
    camera = log.cameras[0]
    out = []
    for frame in shown:
        truth = _image_relpath(seq_id, camera, frame)
        if not store.exists(truth):
            continue
        render_rel = f"renders/{camera}/{frame:06d}.exr"
        if render_rel in stored:
            render = artifact_id(join_relpath(scene_dir(seq_id, scene_hash), render_rel))
        else:
            render = made.add(_rendered(store.root, seq_id, scene_hash, camera, frame))
        out.append(TestComparison(camera, frame, artifact_id(truth), render, render_rel not in stored))
    return tuple(out)


def _reconstruction(store: ArtifactStore, made: MadePictures, seq_id: str, log: SceneLog
                    ) -> ReconstructionQuality | None:
    scenes = list_scenes(store, seq_id)
    if not scenes:
        return None
    scene_hash = scenes[-1]
    manifest = read_scene_manifest(store, seq_id, scene_hash) or {}
    table = store.read_table(join_relpath(scene_dir(seq_id, scene_hash), "metrics.parquet"), METRICS_SCHEMA)
    rows = {r["name"]: r for r in table.select(["name", "value", "unit"]).to_pylist()}
    metrics = {name: float(rows[name]["value"]) for name in QUALITY_METRICS if name in rows}
    units = {name: str(rows[name]["unit"]) for name in metrics}
    stored = set(manifest.get("renders", {}).get("files", []))
    return ReconstructionQuality(scene_hash, len(scenes), metrics, units,
                                 _comparisons(store, made, seq_id, scene_hash, log, stored))


def _objects(store: ArtifactStore, seq_id: str) -> LanguageObjects | None:
    if not list_language_scenes(store, seq_id):
        return None
    prepared = query_scene(store, seq_id, with_relevance=False)
    objects = []
    for node in prepared.scene.nodes:
        labels = node_labels(node)
        location = labels["location_label"] or ""
        sectors = node.static_location
        if not location and sectors:
            location = max(sectors, key=sectors.__getitem__)  # a static object: where it mostly is
        objects.append(LanguageObject(node.node_id, node.object_id, node.category, labels["caption"] or "",
                                      labels["motion"] or "", labels["motion_label"] or "", location))
    return LanguageObjects(prepared.loaded.model_hash, prepared.loaded.language_hash, tuple(objects))


def made_bev(made: MadePictures) -> Callable[[SceneLog], str]:
    """A function drawing a log's bird's-eye view at its middle frame into ``made`` (returns the picture id)."""
    return lambda log: made.add(bev_panel(log, log.num_frames // 2))


def read_sequence(store: ArtifactStore, made: MadePictures, seq_id: str, q: str = "", relevance: bool = False
                  ) -> SequenceView | None:
    """``seq_id``'s page (module docstring), answering the query ``q`` when given; ``None`` when the store has no
    complete log ``seq_id``."""
    if seq_id not in list_logs(store):
        return None
    log = section("log", lambda: read_log(store, seq_id))
    facts = _with_log("log", log, lambda lg: _facts(store, seq_id, lg))
    has_images = facts.value is not None and facts.value.row.images > 0
    text = q.strip()
    return SequenceView(
        seq_id=seq_id, has_images=has_images, facts=facts, bev=_with_log("bird's-eye view", log, made_bev(made)),
        contact_sheet=_with_log("contact sheet", log, lambda lg: _contact_sheet(store, seq_id, lg))
        if has_images else None,
        reconstruction=_with_log("reconstruction quality", log, lambda lg: _reconstruction(store, made, seq_id, lg))
        if has_images else None,
        objects=section("language scene", lambda: _objects(store, seq_id)),
        query=text, relevance=relevance,
        answer=section("query", lambda: answer_sequence_query(store, made, seq_id, text, relevance)) if text else None)
