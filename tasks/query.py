"""Answer one grounding query against a stored, aligned scene (what ``simsplat query`` runs, and the dashboard's
query box).

Not a Prefect task: a query is interactive and takes well under a second once the scene is loaded. Three steps, so
that a long-lived reader (the dashboard) loads a scene once and answers many queries without writing anything:

    prepared = load_query_scene(store, seq_id)                  # the language scene, the log (no pixels), the graph
    grounded = ground_query(store, prepared, "the red car")     # the answer and its picture, in memory
    answer = answer_query(store_root, seq_id, "the red car")    # both, then the picture written as a PNG
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass

import numpy as np

from simsplat_core.language.alignment.feature_field import similarity_map
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.grounding.result import Grounding
from simsplat_core.language.grounding.static_location import with_static_locations
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import default_text_encoder
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scene import SceneGraph
from simsplat_core.types import CameraImage, SceneLog
from simsplat_core.viz.grounding_view import grounding_picture
from storage import ArtifactStore, read_scene_log
from storage.language_scenes import LoadedLanguageScene, read_language_scene
from storage.logs import read_image_rgb
from storage.pictures import write_png

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class QueryScene:
    """A stored language scene ready to answer queries.

    Attributes:
        loaded: the language scene as stored (hashes, records and autoencoder when read ``with_relevance``).
        scene: its ``LanguageScene`` with the static objects' ego-relative sectors filled in from the log.
        log: the sequence's log without pixels (cameras, poses, tracks, map).
        graph: the scene graph with its fitted language features, for relevance maps (``None`` when not read or
            not stored).
    """

    loaded: LoadedLanguageScene
    scene: LanguageScene
    log: SceneLog
    graph: SceneGraph | None


@dataclass(frozen=True, eq=False)
class GroundedQuery:
    """A grounding and its picture, in memory.

    Attributes:
        scene: the language scene searched.
        grounding: the engine's answer.
        frame: the frame drawn (``None`` when nothing was drawn: no node-id maps, a log without cameras).
        picture: ``[H, W, 3]`` uint8: the cameras of ``frame`` with the matched masks outlined, and below them the
            relevance maps when the scene's features were read (``None`` when nothing was drawn).
    """

    scene: LanguageScene
    grounding: Grounding
    frame: int | None
    picture: np.ndarray | None


@dataclass(frozen=True, eq=False)
class QueryAnswer:
    """A grounding plus what was drawn.

    Attributes:
        scene: the language scene searched.
        grounding: the engine's answer.
        frame: the frame drawn (``None`` when nothing was drawn).
        png_uri: where the picture went (``""`` when nothing was drawn: no cameras in the log).
    """

    scene: LanguageScene
    grounding: Grounding
    frame: int | None
    png_uri: str


def default_png_path(store: ArtifactStore, seq_id: str, text: str) -> str:
    """``STORE/queries/<seq_id>/<slug of the text>.png``."""
    slug = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")[:60] or "query"
    return store.uri(f"queries/{seq_id}/{slug}.png")


def load_query_scene(store: ArtifactStore, seq_id: str, *, with_relevance: bool = True, model_hash: str | None = None,
                     language_hash: str | None = None) -> QueryScene:
    """The newest language scene of ``seq_id`` (or the one the hashes name) prepared for :func:`ground_query`;
    ``with_relevance`` also reads the fitted Gaussians and the autoencoder (relevance maps in the picture; slower to
    read and to draw).

    Raises:
        FileNotFoundError: no (such) aligned scene of ``seq_id`` in the store.
    """
    loaded = read_language_scene(store, seq_id, model_hash, language_hash, with_records=with_relevance)
    log = read_scene_log(store, seq_id, load_images=False)
    # static objects' sectors ("the stop sign ahead of us") come from the log's geometry
    node_of_object = {n.object_id: n.node_id for n in loaded.scene.nodes}
    scene = with_static_locations(loaded.scene, AgentStates.from_log(log, node_of_object))
    graph = None
    if loaded.records is not None and loaded.autoencoder is not None:
        graph = SceneGraph.from_records(loaded.records)
    return QueryScene(loaded, scene, log, graph)


def _relevance(prepared: QueryScene, engine: QueryEngine, grounding: Grounding, frame: int,
               views: list[CameraImage]) -> np.ndarray | None:
    """``[C, H, W]`` similarity of the rendered features to the query's appearance part (``None`` without them)."""
    if prepared.graph is None or prepared.loaded.autoencoder is None:
        return None
    phrase = grounding.parsed.appearance or grounding.query  # what the object looks like: the appearance part
    query = engine.embed([phrase])[phrase]
    return similarity_map(prepared.graph, float(frame), np.stack([v.cam_to_world for v in views]),
                          np.stack([v.K for v in views]), views[0].width, views[0].height,
                          prepared.loaded.autoencoder, query)


def ground_query(store: ArtifactStore, prepared: QueryScene, text: str, *, frame: int | None = None,
                 engine: QueryEngine | None = None) -> GroundedQuery:
    """Ground ``text`` in ``prepared`` and draw the answer at ``frame`` (default: where the match is largest), in
    memory; nothing is written.

    Raises:
        ValueError: ``frame`` is not a frame of the scene.
    """
    scene, seq_id = prepared.scene, prepared.scene.seq_id
    engine = engine or QueryEngine(default_text_encoder())
    grounding = engine.ground(scene, text)
    logger.info("%s: %r -> %s", seq_id, text, grounding.node_ids or "no match")
    if scene.node_id_maps is None:
        return GroundedQuery(scene, grounding, None, None)
    all_masks = scene.masks(grounding.node_ids)  # [F, C, H, W]
    if frame is None:
        frame = scene.busiest_frame(all_masks)
    where = np.flatnonzero(scene.frame_indices == frame)
    if where.size == 0:
        raise ValueError(f"{seq_id}: frame {frame} is not in the scene (frames {int(scene.frame_indices[0])}.."
                         f"{int(scene.frame_indices[-1])})")
    masks = all_masks[int(where[0])]  # [C, H, W]
    views = [img for img in prepared.log.images if img.frame_idx == frame]
    views = sorted(views, key=lambda img: scene.cameras.index(img.camera))
    stored = [read_image_rgb(store, seq_id, img.camera, frame) for img in views]
    images = [np.zeros((img.height, img.width, 3), np.float32) if px is None else px for img, px in zip(views, stored)]
    relevance = _relevance(prepared, engine, grounding, frame, views)
    return GroundedQuery(scene, grounding, frame, grounding_picture(images, masks, relevance))


def answer_query(store_root: str, seq_id: str, text: str, *, out: str | None = None, frame: int | None = None,
                 engine: QueryEngine | None = None) -> QueryAnswer:
    """Ground ``text`` in the newest language scene of ``seq_id`` and write the picture to ``out`` (default
    :func:`default_png_path`).

    Raises:
        FileNotFoundError: no aligned scene of ``seq_id`` in the store.
        ValueError: ``frame`` is not a frame of the scene.
    """
    store = ArtifactStore(store_root)
    grounded = ground_query(store, load_query_scene(store, seq_id), text, frame=frame, engine=engine)
    if grounded.picture is None:
        return QueryAnswer(grounded.scene, grounded.grounding, None, "")
    uri = write_png(out or default_png_path(store, seq_id, text), grounded.picture)
    return QueryAnswer(grounded.scene, grounded.grounding, grounded.frame, uri)
