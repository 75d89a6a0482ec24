"""Answer one grounding query against a stored, aligned scene (what ``simsplat query`` runs).

Not a Prefect task: a query is interactive and takes well under a second once the scene is loaded.
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
from simsplat_core.viz.grounding_view import grounding_picture
from storage import ArtifactStore, read_scene_log
from storage.language_scenes import read_language_scene
from storage.logs import read_image_rgb
from storage.pictures import write_png

logger = logging.getLogger(__name__)


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


def answer_query(store_root: str, seq_id: str, text: str, *, out: str | None = None, frame: int | None = None,
                 engine: QueryEngine | None = None) -> QueryAnswer:
    """Ground ``text`` in the newest language scene of ``seq_id`` and draw the answer.

    Raises:
        FileNotFoundError: no aligned scene of ``seq_id`` in the store.
        ValueError: ``frame`` is not a frame of the scene.
    """
    store = ArtifactStore(store_root)
    loaded = read_language_scene(store, seq_id)
    # static objects' sectors ("the stop sign ahead of us") come from the log's geometry
    node_of_object = {n.object_id: n.node_id for n in loaded.scene.nodes}
    states = AgentStates.from_log(read_scene_log(store, seq_id, load_images=False), node_of_object)
    scene = with_static_locations(loaded.scene, states)
    engine = engine or QueryEngine(default_text_encoder())
    grounding = engine.ground(scene, text)
    logger.info("%s: %r -> %s", seq_id, text, grounding.node_ids or "no match")
    if scene.node_id_maps is None:
        return QueryAnswer(scene, grounding, None, "")
    all_masks = scene.masks(grounding.node_ids)  # [F, C, H, W]
    if frame is None:
        frame = scene.busiest_frame(all_masks)
    where = np.flatnonzero(scene.frame_indices == frame)
    if where.size == 0:
        raise ValueError(f"{seq_id}: frame {frame} is not in the scene (frames {int(scene.frame_indices[0])}.."
                         f"{int(scene.frame_indices[-1])})")
    masks = all_masks[int(where[0])]  # [C, H, W]
    log = read_scene_log(store, seq_id, load_images=False)
    views = [img for img in log.images if img.frame_idx == frame]
    views = sorted(views, key=lambda img: scene.cameras.index(img.camera))
    stored = [read_image_rgb(store, seq_id, img.camera, frame) for img in views]
    images = [np.zeros((img.height, img.width, 3), np.float32) if px is None else px for img, px in zip(views, stored)]
    relevance = None
    if loaded.records is not None and loaded.autoencoder is not None:
        graph = SceneGraph.from_records(loaded.records)
        phrase = grounding.parsed.appearance or text  # what the object looks like: the appearance field's part
        query = engine.embed([phrase])[phrase]
        relevance = similarity_map(graph, float(frame), np.stack([v.cam_to_world for v in views]),
                                   np.stack([v.K for v in views]), views[0].width, views[0].height,
                                   loaded.autoencoder, query)
    uri = write_png(out or default_png_path(store, seq_id, text), grounding_picture(images, masks, relevance))
    return QueryAnswer(scene, grounding, frame, uri)
