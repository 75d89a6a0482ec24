"""Search every log of a store by language and draw each hit (what ``simsplat search`` runs).

Not a Prefect task: interactive, like ``simsplat query`` (``saved_search_seeds``, the seed proposals of a mining
configuration's saved searches, runs in a flow as ``tasks.mine.saved_search_seeds_task``). Per log: read the log
(tracks, map; no images), its newest language scene when it is aligned (captions for colours and subtypes, node-id
maps for the picture), compute per-frame object facts once (``simsplat_core.search.frames.log_frames``; cached per log
in ``cache/search_frames/``, ``storage.search_frames``, so a grown store derives only its new logs' facts) and answer
the description (``search_log``). Pictures: the hit's middle frame over every camera with the matched
objects' masks outlined (``viz.grounding_view.grounding_picture``) for aligned logs with camera images,
else a bird's-eye view of that frame (``viz.contact_sheet.bev_panel``) with the matched objects outlined and
their paths (and the ego's, when it is one of them) drawn over the hit's window.
"""

from __future__ import annotations

import functools
import logging
import re
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from simsplat_core import geometry
from simsplat_core.language import motion_labels
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.mining.rule_proposals import Proposal
from simsplat_core.mining.search_seeds import hit_variants
from simsplat_core.scenario import geometry as scenario_geometry
from simsplat_core.scenario import map_context, trajectory, vocabulary
from simsplat_core.scenario.agents import EGO_ID
from simsplat_core.search import frames as search_frames_module
from simsplat_core.search.engine import SearchConfig, SearchHit
from simsplat_core.search.frames import ObjectFrames, log_frames
from simsplat_core.search.logs import SearchableLog, StoreSearch, search_logs
from simsplat_core.types import SceneLog
from simsplat_core.viz.contact_sheet import bev_panel
from simsplat_core.viz.grounding_view import grounding_picture
from storage import ArtifactStore, read_scene_log
from storage import search_frames as search_frames_storage
from storage.errors import StoreNotWritableError
from storage.inventory import require_sequences
from storage.keys import content_key
from storage.language_scenes import read_language_scene
from storage.logs import read_image_rgb, require_log_manifest
from storage.pictures import write_png
from storage.search_frames import frames_to_table, search_frames_cache, table_to_frames
from tasks.code_version import source_digest

logger = logging.getLogger(__name__)


@functools.cache
def search_facts_digest() -> str:
    """The digest of the code that derives a log's search facts (``log_frames`` and what it calls)."""
    return source_digest(*(m.__name__ for m in (search_frames_module, motion_labels, map_context, trajectory,
                                                 scenario_geometry, vocabulary, geometry, search_frames_storage)))


def cached_log_frames(store: ArtifactStore, log: SceneLog, *, write_cache: bool = True) -> dict[str, ObjectFrames]:
    """``log_frames(log)`` from the store's cache when computed for the stored log's content (its manifest key) and
    this code, else computed and cached (a stale or corrupt entry is recomputed, with a warning; a store that cannot
    be written, or ``write_cache`` False (read-only callers such as the dashboard), is searched without caching)."""
    cache = search_frames_cache(store)
    key = content_key(require_log_manifest(store, log.seq_id, "to search")["key"], search_facts_digest())
    cached = cache.load(log.seq_id, key)
    if cached is not None:
        return table_to_frames(cached)
    frames = log_frames(log)
    if not write_cache:
        return frames
    try:
        cache.save(log.seq_id, key, frames_to_table(frames))
    except StoreNotWritableError as exc:
        logger.warning("search facts of %s not cached: %s", log.seq_id, exc)
    return frames


def load_searchable(store: ArtifactStore, seq_id: str, *, write_cache: bool = True) -> SearchableLog:
    """Read ``seq_id`` and its per-frame facts (cached per log content, ``cached_log_frames``); the language scene
    is optional (captions, masks)."""
    log = read_scene_log(store, seq_id, load_images=False)
    try:
        scene: LanguageScene | None = read_language_scene(store, seq_id, with_records=False).scene
    except FileNotFoundError:
        scene = None
        logger.info("%s: not aligned; searching tracks and map only (no colours, BEV pictures)", seq_id)
    return SearchableLog(log, scene, cached_log_frames(store, log, write_cache=write_cache))


def load_store(store_root: str, seq_ids: list[str] | None = None) -> list[SearchableLog]:
    """Every log of the store (or ``seq_ids``), prepared for search.

    Raises:
        FileNotFoundError: the store has no logs, or a named sequence is missing (naming it).
    """
    store = ArtifactStore(store_root)
    return [load_searchable(store, s) for s in require_sequences(store, seq_ids)]


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")[:60] or "search"


def hit_picture(store: ArtifactStore, item: SearchableLog, hit: SearchHit) -> tuple[np.ndarray, str]:
    """``(RGB uint8 picture, kind)`` of a hit's middle frame: ``"cameras"`` (matched masks outlined) when the log is
    aligned with node-id maps and images, else ``"bev"``."""
    frame = hit.middle_frame
    scene = item.scene
    if scene is not None and scene.node_id_maps is not None and scene.maps_valid:
        where = np.flatnonzero(scene.frame_indices == frame)
        node_ids = [n.node_id for n in scene.nodes if n.object_id in hit.object_ids]
        views = sorted((img for img in item.log.images if img.frame_idx == frame),
                       key=lambda img: scene.cameras.index(img.camera) if img.camera in scene.cameras else 99)
        if where.size and views:
            masks = scene.masks(node_ids)[int(where[0])]  # [C, H, W]
            stored = [read_image_rgb(store, item.log.seq_id, v.camera, frame) for v in views]
            images = [np.zeros((v.height, v.width, 3), np.float32) if px is None else px
                      for v, px in zip(views, stored)]
            if len(images) == masks.shape[0]:
                return grounding_picture(images, masks), "cameras"
    return bev_panel(item.log, frame, highlight=hit.object_ids, window=hit.window,
                     highlight_ego=EGO_ID in hit.object_ids), "bev"


def search_store(store_root: str, text: str, *, seq_ids: list[str] | None = None, top: int | None = None,
                 out: str | None = None, pictures: bool = True, config: SearchConfig | None = None) -> StoreSearch:
    """Search every log of the store (or ``seq_ids``) for ``text``; draw the first ``top`` hits' pictures into
    ``out`` (default ``STORE/searches/<slug>/``) as ``<rank>-<seq_id>-<first>-<last>.png``."""
    store = ArtifactStore(store_root)
    items = load_store(store_root, seq_ids)
    found = search_logs(items, text, config)
    by_seq = {i.log.seq_id: i for i in items}
    hits = list(found.hits[:top] if top else found.hits)
    kinds: dict[str, str] = {}
    if pictures:
        folder = (out or store.uri(f"searches/{_slug(text)}")).rstrip("/")
        for rank, hit in enumerate(hits):
            rgb, kind = hit_picture(store, by_seq[hit.seq_id], hit)
            uri = write_png(f"{folder}/{rank + 1:03d}-{hit.seq_id}-{hit.window[0]}-{hit.window[1]}.png", rgb)
            hits[rank] = replace(hit, picture=uri)
            kinds[uri] = kind
    logger.info("search %r: %s", text, found.message)
    return StoreSearch(found.query, tuple(hits), found.results, found.seconds, kinds)


def search_seeds(store_root: str, text: str, *, seq_ids: list[str] | None = None,
                 per_hit: int = 2) -> tuple[StoreSearch, dict[str, list[Proposal]]]:
    """Search the store for ``text`` (no pictures) and turn the hits into the mining loop's seed proposals per
    sequence (``mining.search_seeds.hit_variants``: variants of what each hit's subject does)."""
    items = load_store(store_root, seq_ids)
    found = search_logs(items, text)
    return found, hit_variants(found.hits, object_kinds(items), per_hit)


def object_kinds(items: Sequence[SearchableLog]) -> dict[str, dict[str, str]]:
    """Per sequence, ``object id -> kind`` (``vehicle`` / ``pedestrian`` / ...) of its objects."""
    return {i.log.seq_id: {o: f.kind for o, f in i.objects.items()} for i in items}


def saved_search_seeds(store_root: str, queries: Sequence[str], *, sequences: list[str] | None = None,
                       per_hit: int = 2) -> dict[str, list[Proposal]]:
    """The seed proposals of every saved search in ``queries`` (:func:`search_seeds`, the store's logs read once),
    per sequence of ``sequences`` (default: every log): the first query's first, a wording already seeded by an
    earlier query left out (``tasks.mine.saved_search_seeds_task`` runs it in a flow)."""
    items = load_store(store_root, sequences)
    kinds = object_kinds(items)
    merged: dict[str, list[Proposal]] = {}
    for text in queries:
        found = search_logs(items, text)
        logger.info("saved search %r: %s", text, found.message)
        for seq_id, proposals in hit_variants(found.hits, kinds, per_hit).items():
            seeded = merged.setdefault(seq_id, [])
            seeded += [p for p in proposals if p.prompt not in {s.prompt for s in seeded}]
    return merged
