"""Addresses of dashboard pages, for links the flows publish in their Prefect artifacts.

The URL scheme is fixed (artifacts published by older runs keep working): a run is ``/runs/<run_id>``, a mined
scenario's card ``/scenarios/<run_id>/<seq_id>/<edit_id>``. Every function takes the dashboard's address
(``settings.dashboard_url()``) and returns ``None`` when none is configured, so callers publish no link then.
"""

from __future__ import annotations

from urllib.parse import quote


def _join(base: str | None, *parts: str) -> str | None:
    if not base:
        return None
    return base.rstrip("/") + "".join("/" + quote(part, safe="") for part in parts)


def run_link(base: str | None, run_id: str) -> str | None:
    """``<base>/runs/<run_id>``."""
    return _join(base, "runs", run_id)


def scenario_link(base: str | None, run_id: str, seq_id: str, edit_id: str) -> str | None:
    """``<base>/scenarios/<run_id>/<seq_id>/<edit_id>``."""
    return _join(base, "scenarios", run_id, seq_id, edit_id)
