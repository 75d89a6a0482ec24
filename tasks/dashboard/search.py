"""The search page: a description answered over every log of the store by the engine of ``simsplat search``
(``tasks.search``): ranked hits with their frame windows, the objects that make each hold, and a picture per hit
made in memory (the cameras with the matched masks for aligned logs with images, else a bird's-eye view). Nothing
is written to ``searches/``.

    view = read_search(store, made, "a pedestrian crossing in front of us")

Each log is prepared once per content key (its log and language scene) and kept for the next searches; a log that
does not read is left out and named, the others are still searched.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from simsplat_core.scenario.agents import EGO_ID
from simsplat_core.search.logs import SearchableLog, search_logs
from storage.language_scenes import list_language_scenes
from storage.logs import list_logs, log_dir, read_log_manifest
from storage.store import ArtifactStore
from tasks.dashboard.files import MadePictures
from tasks.dashboard.sections import Section, section
from tasks.search import hit_picture, load_searchable

#: Hits listed (and pictured) by default.
DEFAULT_TOP = 10


@dataclass(frozen=True)
class HitObject:
    """An object that makes a hit hold: its id, category and caption (``""``: the log is not aligned)."""

    object_id: str
    category: str
    caption: str


@dataclass(frozen=True)
class HitView:
    """One ranked hit.

    Attributes:
        rank: 1 for the best; seq_id: the log; window: ``(first, last)`` frame, inclusive; score: in ``[0, 1]``.
        objects: the objects that make it hold (subject first); picture: id of its picture made in memory (``""``
        when it could not be drawn: ``picture_error`` says why); picture_kind: ``"cameras"`` (matched masks
        outlined) or ``"bev"`` (bird's-eye view).
    """

    rank: int
    seq_id: str
    window: tuple[int, int]
    score: float
    objects: tuple[HitObject, ...]
    picture: str
    picture_kind: str
    picture_error: str = ""


@dataclass(frozen=True)
class LogOutcome:
    """How one log answered: its number of hits, or why it has none."""

    seq_id: str
    hits: int
    message: str


@dataclass(frozen=True)
class SearchAnswer:
    """A description answered over the store.

    Attributes:
        text: the description; clauses: the parts it was parsed into; message: the outcome in words.
        hits: the first ``top`` hits, best first; total_hits: how many there are in all.
        logs: every searched log's outcome; unreadable: the logs left out, each with its error.
        seconds: time the search took (without reading the logs or drawing), s.
    """

    text: str
    clauses: tuple[str, ...]
    message: str
    hits: tuple[HitView, ...]
    total_hits: int
    logs: tuple[LogOutcome, ...]
    unreadable: tuple[str, ...]
    seconds: float


@dataclass(frozen=True)
class SearchView:
    """The search page: the ``query`` asked (``""``: none), how many logs the store has, the answer (``None`` when
    nothing was asked)."""

    query: str
    logs: Section[int]
    answer: Section[SearchAnswer] | None


@functools.lru_cache(maxsize=64)
def _prepared(store_root: str, seq_id: str, log_key: str, language: tuple[str, str] | None) -> SearchableLog:
    """A log prepared for search, once per content key (``log_key``, ``language``: a rewritten log or a new
    alignment is prepared again)."""
    return load_searchable(ArtifactStore(store_root), seq_id, write_cache=False)  # the dashboard writes nothing


def searchable(store: ArtifactStore, seq_id: str) -> SearchableLog:
    """``seq_id`` prepared for search (cached per content key).

    Raises:
        FileNotFoundError: no complete log; SchemaError, CorruptArtifactError: a table does not read.
    """
    manifest = read_log_manifest(store, seq_id)
    if manifest is None:
        raise FileNotFoundError(f"{store.uri(log_dir(seq_id))}: no complete log")
    scenes = list_language_scenes(store, seq_id)
    return _prepared(store.root, seq_id, str(manifest.get("key", "")), scenes[0] if scenes else None)


def _hit_objects(item: SearchableLog, object_ids: tuple[str, ...]) -> tuple[HitObject, ...]:
    categories = {o.object_id: o.category for o in item.log.objects}
    nodes = item.nodes or {}
    out = []
    for object_id in object_ids:
        node = nodes.get(object_id)
        caption = node.caption.text if node is not None and node.caption is not None else ""
        out.append(HitObject(object_id, categories.get(object_id, "ego" if object_id == EGO_ID else ""), caption))
    return tuple(out)


def _answer(store: ArtifactStore, made: MadePictures, text: str, top: int) -> SearchAnswer:
    loaded = [section(seq_id, functools.partial(searchable, store, seq_id)) for seq_id in list_logs(store)]
    items = [s.value for s in loaded if s.value is not None]
    found = search_logs(items, text)
    by_seq = {i.log.seq_id: i for i in items}
    hits = []
    for rank, hit in enumerate(found.hits[:top], start=1):
        item = by_seq[hit.seq_id]
        drawn = section(f"picture of hit {rank}", functools.partial(hit_picture, store, item, hit))
        picture, kind = (made.add(drawn.value[0]), drawn.value[1]) if drawn.value is not None else ("", "")
        hits.append(HitView(rank, hit.seq_id, hit.window, hit.score, _hit_objects(item, hit.object_ids),
                            picture, kind, drawn.error))
    return SearchAnswer(text=text, clauses=tuple(c.text for c in found.query.clauses), message=found.message,
                        hits=tuple(hits), total_hits=len(found.hits),
                        logs=tuple(LogOutcome(r.seq_id, len(r.hits), r.message) for r in found.results),
                        unreadable=tuple(s.error for s in loaded if not s.ok), seconds=round(found.seconds, 4))


def read_search(store: ArtifactStore, made: MadePictures, q: str = "", top: int = DEFAULT_TOP) -> SearchView:
    """The search page for the description ``q`` (module docstring); the first ``top`` hits are pictured."""
    text = q.strip()
    logs = section("logs", lambda: len(list_logs(store)))
    answer = section("search", lambda: _answer(store, made, text, max(1, top))) if text else None
    return SearchView(text, logs, answer)
