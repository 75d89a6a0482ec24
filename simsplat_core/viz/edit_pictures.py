"""The pictures of one edit for people: which steps and nodes show it, and the before/after picture built from the
edited renders (collected while they are stored) and the original scene rendered at the chosen frames only.

    shown = ShownFrames()
    for frame in render_frames(edited.graph, log, frames):       # the stored renders of the edit
        shown.add(frame, changed_nodes(edited)[1])
    picture = edit_before_after(log, edited, language, shown, title=prompt)   # uint8 [H', W', 3]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simsplat_core.editing.renders import FrameRender, frame_views, render_frame
from simsplat_core.editing.result import EditedScene
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.types import SceneLog
from simsplat_core.viz.before_after import FramePair, before_after_picture, pick_views, sample_steps
from simsplat_core.viz.images import to_uint8

#: Frames shown in ``before_after.png``.
BEFORE_AFTER_FRAMES = 4


def changed_nodes(edited: EditedScene) -> tuple[np.ndarray, np.ndarray]:
    """Node ids to outline: in the original (removed, replaced, re-tracked) and in the edit (added, re-tracked)."""
    delta = edited.delta
    before = sorted(set(delta.removed_node_ids) | set(delta.retracked))
    after = sorted({a.node_id for a in delta.added} | set(delta.retracked))
    return np.asarray(before, np.int32), np.asarray(after, np.int32)


def active_steps(edited: EditedScene) -> np.ndarray:
    """``[T]`` bool: the steps where an edited, inserted or removed agent exists."""
    before, after = edited.original_states, edited.states
    active = np.zeros(after.num_steps, bool)
    for r, source in enumerate(after.sources):
        if source in ("edited", "inserted"):
            active |= after.valid[r]
    for oid in set(before.object_ids) - set(after.object_ids):
        active |= before.valid[before.index(oid)]
    return active


def original_pixels(language: LanguageScene, frames: list[int], cameras: tuple[str, ...], nodes: np.ndarray
                    ) -> np.ndarray:
    """``[F, C]`` pixels of ``nodes`` in the stored scene's node-id maps (zeros where it has none)."""
    out = np.zeros((len(frames), len(cameras)), np.int64)
    maps = language.node_id_maps
    if maps is None or not language.maps_valid or not len(nodes):
        return out
    rows = {int(f): k for k, f in enumerate(language.frame_indices)}
    cols = {c: k for k, c in enumerate(language.cameras)}
    for i, f in enumerate(frames):
        for j, c in enumerate(cameras):
            if f in rows and c in cols:
                out[i, j] = int(np.isin(maps[rows[f], cols[c]], nodes).sum())
    return out


@dataclass
class ShownFrames:
    """What the before/after picture needs of the edited renders: per frame the uint8 images and the edited
    objects' pixels (kept for every frame: which ones show the edit is known only at the end)."""

    frames: list[int] = field(default_factory=list)
    cameras: tuple[str, ...] = ()
    images: list[list[np.ndarray]] = field(default_factory=list)
    masks: list[list[np.ndarray]] = field(default_factory=list)

    def add(self, frame: FrameRender, nodes: np.ndarray) -> None:
        """Keep one rendered frame (every camera; ``node_id`` rendered) and the pixels of ``nodes`` in it."""
        assert frame.node_id is not None
        self.frames.append(frame.frame_idx)
        self.cameras = frame.cameras
        self.images.append([to_uint8(np.clip(rgb, 0.0, 1.0)) for rgb in frame.rgb])
        self.masks.append([np.isin(ids, nodes) for ids in frame.node_id])

    def pixels(self) -> np.ndarray:
        """``[F, C]`` pixels of the edited objects per kept frame and camera."""
        return np.array([[int(m.sum()) for m in row] for row in self.masks], np.int64).reshape(len(self.frames), -1)


def edit_before_after(log: SceneLog, edited: EditedScene, language: LanguageScene, shown: ShownFrames, title: str,
                      active: np.ndarray) -> np.ndarray:
    """Original over edited at up to :data:`BEFORE_AFTER_FRAMES` frames that show the edit (the original rendered
    here, at those frames only); ``active [T]``: :func:`active_steps`. Returns uint8 ``[H', W', 3]``."""
    before_nodes, _ = changed_nodes(edited)
    pixels = shown.pixels() + original_pixels(language, shown.frames, shown.cameras, before_nodes)
    views = pick_views(pixels, BEFORE_AFTER_FRAMES)
    if not views:  # nothing visible: the frames where the edited agents exist, first camera
        steps = sample_steps(active, BEFORE_AFTER_FRAMES)
        wanted = {int(edited.states.frame_idx[s]) for s in steps}
        views = [(row, 0) for row, f in enumerate(shown.frames) if f in wanted]
    pairs = []
    for row, cam in views:
        frame_idx = shown.frames[row]
        before = render_frame(edited.original, frame_idx, frame_views(log, frame_idx))
        assert before.node_id is not None
        k = before.cameras.index(shown.cameras[cam])
        t = float(edited.states.times[int(np.searchsorted(edited.states.frame_idx, frame_idx))])
        pairs.append(FramePair(f"t={t:.1f}s {shown.cameras[cam]}", before.rgb[k], shown.images[row][cam],
                               np.isin(before.node_id[k], before_nodes), shown.masks[row][cam]))
    return before_after_picture(pairs, title=title)
