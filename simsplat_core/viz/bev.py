"""Bird's-eye view of an edit: the map, every agent's box at one step, old and new paths, a legend.

    picture = edit_bev(log.map_features, edited.original_states, edited.states, title=prompt)  # uint8 [S, S, 3]

World frame (the log's first ego pose), x up, y to the left, equal scale; the view is fitted to the ego's
path and the paths of every changed agent (with a margin). Agents whose ``source`` is ``"edited"`` are
drawn orange (old path dashed grey, new path solid, the box filled at the drawn step and outlined where it
ends), ``"inserted"`` cyan, ``"refined"`` (agents that reacted to the edit, ``motion.refine``) green with
their log path dashed grey, removed agents (in ``before`` but not in ``after``) red with a cross; unchanged
agents in their category colour, the ego yellow. Dots on the new paths mark every second. Pure numpy + OpenCV.

``bev_extent`` gives the fitted view so several pictures (the frames of ``viz.bev_animation``) share it.
"""

from __future__ import annotations

import logging

import cv2
import numpy as np

from simsplat_core.geometry import box_corners_batch
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.types import MapFeature
from simsplat_core.viz.contact_sheet import CATEGORY_COLORS, draw_map

logger = logging.getLogger(__name__)

EGO_COLOR = (255, 255, 0)
EDITED_COLOR = (255, 150, 0)
INSERTED_COLOR = (0, 230, 255)
REMOVED_COLOR = (255, 40, 40)
REFINED_COLOR = (90, 230, 110)
OLD_PATH_COLOR = (190, 190, 190)
BACKGROUND = 20


def _dashed(canvas: np.ndarray, pts: np.ndarray, color: tuple[int, int, int], dash_px: float = 6.0) -> None:
    """A dashed polyline through ``pts [P, 2]`` (int pixels)."""
    on, left = True, dash_px
    for a, b in zip(pts[:-1].astype(np.float64), pts[1:].astype(np.float64)):
        seg = float(np.linalg.norm(b - a))
        pos = 0.0
        while pos < seg:
            step = min(left, seg - pos)
            if on:
                p = np.round(a + (b - a) * (pos / seg)).astype(int)
                q = np.round(a + (b - a) * ((pos + step) / seg)).astype(int)
                cv2.line(canvas, (int(p[0]), int(p[1])), (int(q[0]), int(q[1])), color, 1, cv2.LINE_AA)
            pos += step
            left -= step
            if left <= 1e-9:
                on, left = not on, dash_px


class _View:
    """World xy -> pixels of a square canvas of ``size`` covering ``[lo, hi]`` (x up, y left)."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray, size: int) -> None:
        self.center = (lo + hi) / 2.0
        self.px_per_m = size / float(max(hi - lo))
        self.size = size

    def __call__(self, points: np.ndarray) -> np.ndarray:
        p = np.asarray(points, np.float64)[..., :2] - self.center
        u = self.size / 2.0 - p[..., 1] * self.px_per_m
        v = self.size / 2.0 - p[..., 0] * self.px_per_m
        return np.round(np.stack([u, v], axis=-1)).astype(np.int32)


def _extent(before: AgentStates, after: AgentStates, focus: list[tuple[AgentStates, int]], margin_m: float,
            min_extent_m: float) -> tuple[np.ndarray, np.ndarray]:
    pts = [after.xy[after.index(EGO_ID)][after.valid[after.index(EGO_ID)]]] if EGO_ID in after.object_ids else []
    pts += [states.xy[row][states.valid[row]] for states, row in focus]
    allpts = np.concatenate([p for p in pts if len(p)]) if any(len(p) for p in pts) else np.zeros((1, 2))
    lo, hi = allpts.min(axis=0) - margin_m, allpts.max(axis=0) + margin_m
    span = max(float(max(hi - lo)), min_extent_m)
    mid = (lo + hi) / 2.0
    return mid - span / 2.0, mid + span / 2.0


def _legend(canvas: np.ndarray, entries: list[tuple[str, tuple[int, int, int], str]]) -> None:
    """Legend box at the top right: ``(label, colour, style)`` with style ``box`` / ``line`` / ``dash`` / ``cross``."""
    row_h, width = 14, 118
    x0 = canvas.shape[1] - width - 6
    y0 = 6
    cv2.rectangle(canvas, (x0, y0), (x0 + width, y0 + row_h * len(entries) + 6), (0, 0, 0), -1)
    for i, (label, color, style) in enumerate(entries):
        y = y0 + 10 + i * row_h
        a, b = (x0 + 6, y), (x0 + 26, y)
        if style == "box":
            cv2.rectangle(canvas, (x0 + 8, y - 4), (x0 + 24, y + 4), color, 1)
        elif style == "dash":
            _dashed(canvas, np.array([a, b]), color, 4.0)
        elif style == "cross":
            cv2.rectangle(canvas, (x0 + 8, y - 4), (x0 + 24, y + 4), color, 1)
            cv2.line(canvas, (x0 + 8, y - 4), (x0 + 24, y + 4), color, 1)
        else:
            cv2.line(canvas, a, b, color, 2, cv2.LINE_AA)
        cv2.putText(canvas, label, (x0 + 32, y + 4), cv2.FONT_HERSHEY_SIMPLEX, 0.36, (230, 230, 230), 1, cv2.LINE_AA)


def default_step(before: AgentStates, after: AgentStates) -> int:
    """The first step at which any edited / inserted agent exists (0 when none does)."""
    rows = [r for r, s in enumerate(after.sources) if s in ("edited", "inserted")]
    valid = after.valid[rows].any(axis=0) if rows else np.zeros(after.num_steps, bool)
    return int(np.argmax(valid)) if valid.any() else 0


CHANGED_SOURCES: tuple[str, ...] = ("edited", "inserted", "refined")
_SOURCE_COLOR = {"edited": EDITED_COLOR, "inserted": INSERTED_COLOR, "refined": REFINED_COLOR}


def _changed_rows(before: AgentStates, after: AgentStates) -> tuple[list[int], list[int], list[int]]:
    """Rows of ``after`` that the edit changed, of ``before`` for their old paths, and of removed agents."""
    removed = [before.index(o) for o in before.object_ids if o not in after.object_ids]
    changed = [r for r, s in enumerate(after.sources) if s in CHANGED_SOURCES]
    old_rows = [before.index(after.object_ids[r]) for r in changed if after.object_ids[r] in before.object_ids]
    return changed, old_rows, removed


def bev_extent(before: AgentStates, after: AgentStates, margin_m: float = 12.0, min_extent_m: float = 40.0
               ) -> tuple[np.ndarray, np.ndarray]:
    """``([2], [2])`` world corners of the view :func:`edit_bev` fits to the ego and the changed agents."""
    changed, old_rows, removed = _changed_rows(before, after)
    focus = [(after, r) for r in changed] + [(before, r) for r in removed + old_rows]
    return _extent(before, after, focus, margin_m, min_extent_m)


def _footprint(view: _View, states: AgentStates, row: int, k: int) -> np.ndarray:
    """``[4, 2]`` int32 canvas corners of agent ``row``'s box at step ``k``."""
    center = np.append(states.xy[row, k], states.z[row, k])
    corners = box_corners_batch(center[None], states.size[row][None], states.heading[row, k:k + 1])[0, :4]
    return view(corners)


def _path(view: _View, states: AgentStates, row: int) -> np.ndarray:
    """``[K, 2]`` int32 canvas points of agent ``row``'s valid steps."""
    return view(states.xy[row][states.valid[row]])


def _draw_unchanged(canvas: np.ndarray, view: _View, after: AgentStates, changed: list[int], step: int) -> None:
    """Unchanged agents: boxes in their category colour (and the ego's path)."""
    for r, oid in enumerate(after.object_ids):
        if r in changed or not after.valid[r, step]:
            continue
        if oid == EGO_ID:
            pts = _path(view, after, r)
            cv2.polylines(canvas, [pts], False, EGO_COLOR, 1, cv2.LINE_AA)
            cv2.fillPoly(canvas, [_footprint(view, after, r, step)], EGO_COLOR)
            continue
        color = CATEGORY_COLORS.get(after.categories[r], CATEGORY_COLORS["other"])
        box = _footprint(view, after, r, step)
        cv2.polylines(canvas, [box], True, color, 1, cv2.LINE_AA)
        cv2.line(canvas, tuple(int(v) for v in box[0]), tuple(int(v) for v in box[3]), (255, 255, 255), 1)


def _draw_old_paths(canvas: np.ndarray, view: _View, before: AgentStates, old_rows: list[int]) -> None:
    """The changed agents' paths before the edit, dashed."""
    for r in old_rows:
        pts = _path(view, before, r)
        if len(pts) > 1:
            _dashed(canvas, pts, OLD_PATH_COLOR)


def _draw_removed(canvas: np.ndarray, view: _View, before: AgentStates, removed: list[int], step: int) -> None:
    """Removed agents: dashed path and a crossed-out box (at ``step``, or their first valid step)."""
    for r in removed:
        pts = _path(view, before, r)
        if len(pts) > 1:
            _dashed(canvas, pts, REMOVED_COLOR)
        k = step if before.valid[r, step] else int(np.argmax(before.valid[r]))
        box = _footprint(view, before, r, k)
        cv2.polylines(canvas, [box], True, REMOVED_COLOR, 1, cv2.LINE_AA)
        cv2.line(canvas, tuple(int(v) for v in box[0]), tuple(int(v) for v in box[2]), REMOVED_COLOR, 1)
        cv2.line(canvas, tuple(int(v) for v in box[1]), tuple(int(v) for v in box[3]), REMOVED_COLOR, 1)


def _draw_changed(canvas: np.ndarray, view: _View, after: AgentStates, changed: list[int], step: int) -> None:
    """New paths: solid, a dot per second, the box at ``step`` (filled) and where it ends up (outline), labelled."""
    seconds = np.round(after.times - after.times[0], 6)
    for r in changed:
        color = _SOURCE_COLOR[after.sources[r]]
        pts = _path(view, after, r)
        if len(pts) > 1:
            cv2.polylines(canvas, [pts], False, color, 2, cv2.LINE_AA)
        ticks = after.valid[r] & (np.abs(seconds - np.round(seconds)) < 1e-3)
        for p in view(after.xy[r][ticks]):
            cv2.circle(canvas, (int(p[0]), int(p[1])), 2, color, -1, cv2.LINE_AA)
        k = step if after.valid[r, step] else int(np.argmax(after.valid[r]))
        last = int(after.num_steps - 1 - np.argmax(after.valid[r][::-1]))
        if last != k:  # where it ends up: outline only
            cv2.polylines(canvas, [_footprint(view, after, r, last)], True, color, 1, cv2.LINE_AA)
        box = _footprint(view, after, r, k)
        cv2.fillPoly(canvas, [box], tuple(int(c * 0.5) for c in color))
        cv2.polylines(canvas, [box], True, color, 1, cv2.LINE_AA)
        cv2.line(canvas, tuple(int(v) for v in box[0]), tuple(int(v) for v in box[3]), (255, 255, 255), 1)
        label = after.object_ids[r][:14]
        cv2.putText(canvas, label, (int(box[:, 0].max()) + 3, int(box[:, 1].min()) + 4), cv2.FONT_HERSHEY_SIMPLEX,
                    0.36, color, 1, cv2.LINE_AA)


def edit_bev(map_features: tuple[MapFeature, ...] | list[MapFeature], before: AgentStates, after: AgentStates, *,
             step: int | None = None, title: str = "", size: int = 640, margin_m: float = 12.0,
             min_extent_m: float = 40.0, extent: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """The bird's-eye view of an edit (module docstring).

    Args:
        before, after: the agents before and after the edit (same steps).
        step: the step whose boxes are drawn (default: :func:`default_step`).
        title: drawn at the top left (e.g. the prompt).
        extent: world ``(lo [2], hi [2])`` to show (default: :func:`bev_extent`).

    Returns:
        ``[size, size, 3]`` uint8 RGB.
    """
    if before.num_steps != after.num_steps:
        raise ValueError(f"edit_bev: before has {before.num_steps} steps, after {after.num_steps}")
    step = default_step(before, after) if step is None else int(step)
    if not 0 <= step < after.num_steps:
        raise ValueError(f"edit_bev: step {step} outside [0, {after.num_steps})")
    changed, old_rows, removed = _changed_rows(before, after)
    lo, hi = bev_extent(before, after, margin_m, min_extent_m) if extent is None else extent
    view = _View(lo, hi, size)
    canvas = np.full((size, size, 3), BACKGROUND, np.uint8)
    draw_map(canvas, map_features, view)

    _draw_unchanged(canvas, view, after, changed, step)
    _draw_old_paths(canvas, view, before, old_rows)
    _draw_removed(canvas, view, before, removed, step)
    _draw_changed(canvas, view, after, changed, step)
    entries = [("ego", EGO_COLOR, "line"), ("log agent", CATEGORY_COLORS["vehicle"], "box"),
               ("old path", OLD_PATH_COLOR, "dash"), ("edited", EDITED_COLOR, "line"),
               ("inserted", INSERTED_COLOR, "line"), ("reacted", REFINED_COLOR, "line"),
               ("removed", REMOVED_COLOR, "cross")]
    _legend(canvas, entries)
    metres = (hi - lo)[0]
    header = f"t={after.times[step]:.1f}s (frame {int(after.frame_idx[step])}), {metres:.0f} m across"
    cv2.putText(canvas, header, (6, size - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (230, 230, 230), 1, cv2.LINE_AA)
    if title:
        cv2.putText(canvas, title[:80], (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (255, 255, 255), 1, cv2.LINE_AA)
    return canvas
