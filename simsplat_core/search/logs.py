"""Search over several prepared logs: one description answered over every log, hits ranked together.

    items = [SearchableLog(log, language_scene_or_None, log_frames(log)), ...]
    found = search_logs(items, "a car following the bus")
    found.hits, found.message

Pure: the logs are read (and pictures drawn) by ``tasks.search``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property

from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.search.describe import SearchQuery, parse_description
from simsplat_core.search.engine import SearchConfig, SearchHit, SearchResult, search_log
from simsplat_core.search.frames import ObjectFrames
from simsplat_core.types import SceneLog


@dataclass(frozen=True, eq=False)
class SearchableLog:
    """One log prepared for search: the log (no pixels), its language scene (``None``: not aligned), per-frame facts."""

    log: SceneLog
    scene: LanguageScene | None
    objects: dict[str, ObjectFrames]

    @cached_property
    def nodes(self) -> dict[str, NodeLanguage] | None:
        return None if self.scene is None else {n.object_id: n for n in self.scene.nodes}


@dataclass(frozen=True)
class StoreSearch:
    """A description answered over a store: ranked hits of every log, each log's result, seconds taken."""

    query: SearchQuery
    hits: tuple[SearchHit, ...]
    results: tuple[SearchResult, ...]
    seconds: float
    picture_kinds: dict[str, str]

    @property
    def message(self) -> str:
        if self.hits:
            return f"{len(self.hits)} hits in {len({h.seq_id for h in self.hits})} of {len(self.results)} logs"
        reasons = "; ".join(r.message for r in self.results)
        return f"no log matches {self.query.text!r}: {reasons}"


def search_logs(items: list[SearchableLog], text: str, config: SearchConfig | None = None) -> StoreSearch:
    """Answer ``text`` over prepared logs (no pictures); hits ranked over all logs."""
    t0 = time.perf_counter()
    query = parse_description(text)
    results = tuple(search_log(i.log.seq_id, i.objects, i.log.num_frames, query, i.nodes, config) for i in items)
    hits = sorted((h for r in results for h in r.hits), key=lambda h: (-h.score, h.seq_id, h.window[0]))
    return StoreSearch(query, tuple(hits), results, time.perf_counter() - t0, {})


__all__ = ["SearchableLog", "StoreSearch", "search_logs"]
