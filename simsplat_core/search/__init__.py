"""Search the logs by language: which objects match a description and in which frame windows it holds.

``describe`` parses a description into agent clauses and relations, ``frames`` computes per-frame facts of
every object (motion by the auto-labeller's rules on sliding windows, ego sector, map context), ``windows``
turns per-frame truth into frame windows and ``engine`` answers a description over one log.
"""

from simsplat_core.search.describe import AgentClause, SearchQuery, parse_description
from simsplat_core.search.engine import SearchHit, SearchResult, search_log

__all__ = ["AgentClause", "SearchQuery", "parse_description", "SearchHit", "SearchResult", "search_log"]
