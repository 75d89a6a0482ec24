"""The sequence page's query box: a description grounded in the log's language scene by the engine of ``simsplat
query`` (``tasks.query``), answered in memory: the matched objects with their scores, the cameras with the matched
masks outlined (and the relevance maps when asked), and the bird's-eye view with the matched objects and their
paths. Nothing is written to the store; the pictures go to the dashboard's ``MadePictures``.

    result = answer_sequence_query(store, made, "synth-000000", "the red car turning right")

A language scene is read once per (sequence, language hash) and kept for the next queries; a newer alignment of the
log is read when it appears.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass

from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.grounding.result import NodeMatch
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import default_text_encoder
from simsplat_core.viz.contact_sheet import bev_panel
from storage.language_scenes import list_language_scenes
from storage.store import ArtifactStore
from tasks.answers import node_labels
from tasks.dashboard.files import MadePictures
from tasks.query import QueryScene, ground_query, load_query_scene

#: Scored objects listed below the matches.
RANKED = 8


@dataclass(frozen=True)
class MatchedObject:
    """One scored object node.

    Attributes:
        node_id, object_id, category: the node and its log object.
        caption, motion, location: what the language scene says of it (``""`` when it says nothing).
        score: the combined match score in ``[0, 1]``; appearance, motion_score, location_score: each signal's score
            (``nan``, JSON ``null``: the query did not use that signal).
        chosen: it is one of the answer's matches.
    """

    node_id: int
    object_id: str
    category: str
    caption: str
    motion: str
    location: str
    score: float
    appearance: float
    motion_score: float
    location_score: float
    chosen: bool


@dataclass(frozen=True)
class QueryResult:
    """A description answered on one log.

    Attributes:
        text: the description; message: what was found, or why nothing was; group: it asked for every match.
        matches: the chosen objects, best first; ranking: the best scored objects (:data:`RANKED`).
        frame: the frame drawn (``None``: the log has no node-id maps, so only the bird's-eye view is drawn).
        picture: id of the cameras with the matched masks (``""``: none drawn); bev: id of the bird's-eye view.
        seconds: time taken to answer, s.
    """

    text: str
    message: str
    group: bool
    matches: tuple[MatchedObject, ...]
    ranking: tuple[MatchedObject, ...]
    frame: int | None
    picture: str
    bev: str
    seconds: float


@functools.lru_cache(maxsize=1)
def _engine() -> QueryEngine:
    """One engine for every query (the text encoder and its cache are shared)."""
    return QueryEngine(default_text_encoder())


@functools.lru_cache(maxsize=6)
def _loaded(store_root: str, seq_id: str, model_hash: str, language_hash: str, with_relevance: bool) -> QueryScene:
    return load_query_scene(ArtifactStore(store_root), seq_id, with_relevance=with_relevance, model_hash=model_hash,
                            language_hash=language_hash)


def query_scene(store: ArtifactStore, seq_id: str, *, with_relevance: bool) -> QueryScene:
    """The newest language scene of ``seq_id`` prepared for queries, read once per language hash.

    Raises:
        FileNotFoundError: the log is not aligned (naming the command that aligns it).
    """
    scenes = list_language_scenes(store, seq_id)
    if not scenes:
        raise FileNotFoundError(f"no language scene of {seq_id!r} in {store.uri('alignment')} (run `simsplat align "
                                f"--store {store.root}` or `simsplat run`): nothing to ground a description in")
    model_hash, language_hash = scenes[0]
    return _loaded(store.root, seq_id, model_hash, language_hash, with_relevance)


def _matched(scene: LanguageScene, match: NodeMatch, chosen: bool) -> MatchedObject:
    node = scene.node(match.node_id)
    labels = node_labels(node)
    return MatchedObject(match.node_id, match.object_id, node.category, labels["caption"] or "",
                         labels["motion"] or "", labels["location_label"] or "", match.score, match.appearance,
                         match.motion, match.location, chosen)


def answer_sequence_query(store: ArtifactStore, made: MadePictures, seq_id: str, text: str, relevance: bool = False
                          ) -> QueryResult:
    """Ground ``text`` in ``seq_id``'s newest language scene (module docstring); ``relevance`` adds the relevance
    maps of the query's appearance part under the cameras (renders the scene's features: seconds on a CPU).

    Raises:
        FileNotFoundError: the log is not aligned; OSError, CorruptArtifactError: a stored file does not read.
    """
    t0 = time.perf_counter()
    prepared = query_scene(store, seq_id, with_relevance=relevance)
    grounded = ground_query(store, prepared, text, engine=_engine())
    grounding, scene = grounded.grounding, grounded.scene
    chosen = set(grounding.node_ids)
    picture = made.add(grounded.picture) if grounded.picture is not None else ""
    log = prepared.log
    frame = grounded.frame if grounded.frame is not None else log.num_frames // 2
    bev = made.add(bev_panel(log, frame, highlight=tuple(m.object_id for m in grounding.matches),
                             window=(0, log.num_frames - 1)))
    return QueryResult(
        text=text, message=grounding.message, group=grounding.group,
        matches=tuple(_matched(scene, m, True) for m in grounding.matches),
        ranking=tuple(_matched(scene, m, m.node_id in chosen) for m in grounding.ranking[:RANKED]),
        frame=grounded.frame, picture=picture, bev=bev, seconds=round(time.perf_counter() - t0, 3))

