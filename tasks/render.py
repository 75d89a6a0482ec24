"""Render a stored scene at one frame from the log's cameras, optionally shifted, and write the PNG (what
``simsplat render`` runs).

Not a Prefect task: interactive, one frame. Thin: check the sequence has a complete log, read it (no pixels) and its
scene, render every chosen camera (``simsplat_core.scene_view``) in memory (:func:`render_frame`, which the
dashboard uses too), write the cameras side by side.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from simsplat_core.scene import SceneGraph
from simsplat_core.scene_view import render_views, shifted_cameras, side_by_side
from storage import ArtifactStore, read_scene, read_scene_log
from storage.inventory import require_sequences
from storage.pictures import write_png

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class RenderedView:
    """Where the picture went (``uri``) and the scene rendered (``scene_hash``)."""

    uri: str
    scene_hash: str


def render_frame(store: ArtifactStore, seq_id: str, frame: int, *, cameras: list[str] | None = None,
                 shift_left: float = 0.0, shift_forward: float = 0.0, scene_hash: str | None = None
                 ) -> tuple[list[np.ndarray], str]:
    """``([H, W, 3] float32 RGB per camera, scene hash)``: ``seq_id``'s scene (the newest, or the one ``scene_hash``
    names: a unique prefix is enough) rendered at ``frame`` from ``cameras`` (default: all, log order), moved
    ``shift_left`` / ``shift_forward`` metres in the ego frame; in memory, nothing is written.

    Raises:
        MissingInputError: no complete log ``seq_id`` (naming the available ones).
        FileNotFoundError, ValueError: no (such) reconstructed scene (naming what to run), frame or camera.
    """
    require_sequences(store, [seq_id])
    log = read_scene_log(store, seq_id, load_images=False)
    loaded = read_scene(store, seq_id, scene_hash)
    views = shifted_cameras(log, frame, cameras, shift_left=shift_left, shift_forward=shift_forward)
    return render_views(SceneGraph.from_records(loaded.records), frame, views), loaded.scene_hash


def render_view(store_root: str, seq_id: str, frame: int, out: str, *, cameras: list[str] | None = None,
                shift_left: float = 0.0, shift_forward: float = 0.0, scene_hash: str | None = None) -> RenderedView:
    """Render ``seq_id``'s scene at ``frame`` (:func:`render_frame`) and write the cameras side by side to ``out``
    (a ``.png`` path or URI).

    Raises:
        MissingInputError: no complete log ``seq_id`` (naming the available ones).
        FileNotFoundError, ValueError: no (such) reconstructed scene (naming what to run), frame or camera; ``out``
            is not a ``.png``.
    """
    images, rendered_hash = render_frame(ArtifactStore(store_root), seq_id, frame, cameras=cameras,
                                         shift_left=shift_left, shift_forward=shift_forward, scene_hash=scene_hash)
    return RenderedView(write_png(out, side_by_side(images)), rendered_hash)
