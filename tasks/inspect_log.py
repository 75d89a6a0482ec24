"""Summarise a stored log and draw its contact sheet (what ``simsplat inspect`` runs).

Not a Prefect task: interactive. Reads the log (pixels only when a sheet is drawn), summarises it
(``simsplat_core.summary``) and writes the contact sheet (every camera with its projected 3D boxes, and a bird's-eye
view) as a PNG.
"""

from __future__ import annotations

import os

from simsplat_core.summary import LogSummary, summarize_log
from simsplat_core.viz.contact_sheet import contact_sheet
from storage import ArtifactStore, read_scene_log
from storage.pictures import write_png


def inspect_log(store_root: str, seq_id: str, sheet: str | os.PathLike[str] | None = None, frame: int = 0
                ) -> tuple[LogSummary, str]:
    """``(summary, contact sheet URI)`` of ``STORE/logs/<seq_id>`` (``""`` when no ``sheet`` path is given).

    Raises:
        FileNotFoundError: no complete log ``seq_id``.
        OSError, ValueError: the contact sheet could not be drawn or written (e.g. no such frame, not a ``.png``).
    """
    log = read_scene_log(ArtifactStore(store_root), seq_id, load_images=sheet is not None)
    summary = summarize_log(log)
    uri = write_png(sheet, contact_sheet(log, frame)) if sheet is not None else ""
    return summary, uri
