"""Does an inserted object read as the asked colour where it stands? Exposure matching, else another asset.

An asset keeps the light of the scene it was cut from: a white car whose rear was in shade there shows a
grey rear wherever it is inserted, and "add a white car 20 m ahead" would put a silver one on the road.
White, silver, grey and black differ only in lightness, so the fix is an exposure gain, not a recolour. A hue
is checked too but never exposure-matched: one that reads as another colour (blue as purple) is another asset's
job.

After the edited graph is built, every added node whose command asked a colour (a vehicle's or
static object's body, a pedestrian's top) is rendered with the whole edited scene, occlusions included, at up
to ``LOOK_FRAMES`` frames where it exists, from the cameras its box (grown by ``BOX_MARGIN_M``) may show in
(``look_renders``). The built-in captioner (``language.appearance.captioner.describe_track``, the same one
that captions the scene for grounding) names its main colour from the crops with at least ``MIN_LOOK_PIXELS``
of its pixels; it reads as asked when the track's colour is the asked one and the crops that are cover
``LOOK_SHARE`` of its pixels. Otherwise the crops are re-captioned under the gains of ``BRIGHTER_GAINS``
(asked grey lighter) or ``DARKER_GAINS`` (darker; greys only), and the first gain under which they read as
asked becomes an exposure variant of the asset (``colors.exposed``, id ``<asset>~exp<gain>``): the delta names the
variant, so a stored edit rebuilds to the same pixels. The gain is verified on a render of the variant and raised
along its ladder when it falls short (``VERIFY_ROUNDS`` renders at most). A node that still does not
read as asked is reported (``LookNote.fitted`` false): ``editing.apply`` then tries the program again without
that asset (``apply.LOOK_RETRIES`` times).

    delta, graph, notes = match_exposure(log, graph, delta, wanted, states, asset_of, build)
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from simsplat_core import geometry
from simsplat_core.color_names import ACHROMATIC_NAMES, COLOR_NAMES
from simsplat_core.editing.assets.colors import exposure_suffix
from simsplat_core.editing.assets.record import VARIANT_SEP, Asset
from simsplat_core.editing.renders import FrameRender, frame_views, render_frame
from simsplat_core.editing.result import AddedNode, EditDelta
from simsplat_core.language.appearance.captioner import describe_object, describe_track, subtype_from_size
from simsplat_core.language.appearance.crops import ObjectCrop, crop_object
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: Frames an added object is looked at (evenly spread over the steps where it exists).
LOOK_FRAMES = 20
#: A view shows the object when at least this many pixels are its own (the evaluation's caption floor).
MIN_LOOK_PIXELS = 40
#: The object reads as the asked colour when the track does and the crops that do cover this share of its
#: pixels (the captioner lets silver win over white on a tenth of the area).
LOOK_SHARE = 0.98
#: Gains tried, in order, when the asked colour is lighter / darker than what the object reads as.
BRIGHTER_GAINS = (1.1, 1.2, 1.3, 1.45, 1.6, 1.8)
DARKER_GAINS = (0.9, 0.8, 0.7, 0.6)
#: A camera is rendered when the object's box grown by this much (m) may show in it (Gaussians reach past the box).
BOX_MARGIN_M = 0.5
#: Renders verifying (and, when needed, raising) the gains.
VERIFY_ROUNDS = 2
#: Categories checked: one body colour, or a pedestrian's top (the captioner's main colour of a pedestrian; the
#: gain of a pedestrian's variant scales its upper body only, ``editing.assets.colors.exposed``).
CHECKED_CATEGORIES = ("vehicle", "static", "pedestrian")


@dataclasses.dataclass(frozen=True)
class LookNote:
    """What the check found for one added node.

    Attributes:
        node_id: the added node.
        wanted: the asked colour.
        seen: the colour the captioner named before any gain (``None``: too small to caption anywhere).
        gain: the exposure gain applied (``1.0``: none was needed or none fitted).
        verified: a render (of the variant, when a gain is applied) reads as ``wanted`` in ``LOOK_SHARE`` of the
            object's pixels.
        final: the colour the captioner names on the last render (``None``: too small to caption).
    """

    node_id: int
    wanted: str
    seen: str | None
    gain: float
    verified: bool = False
    final: str | None = None

    @property
    def fitted(self) -> bool:
        """It reads as asked (as it was, or under its gain, verified on a render)."""
        return self.verified

    def describe(self) -> str:
        if self.seen is None:
            return f"node {self.node_id} is too small to check its colour ({self.wanted} asked)"
        if self.gain != 1.0:
            return (f"node {self.node_id} read as {self.seen}, exposure x{self.gain:.2f} "
                    + (f"makes it {self.wanted}" if self.verified else f"does not make it {self.wanted} everywhere"))
        if self.seen != self.wanted:
            return f"node {self.node_id} reads as {self.seen} here, not {self.wanted} (no exposure gain fits)"
        return f"node {self.node_id} reads as {self.wanted}"


def look_frames(states: AgentStates, object_id: str, count: int = LOOK_FRAMES) -> list[int]:
    """Up to ``count`` log frames, evenly spread over the steps where ``object_id`` exists."""
    valid = np.nonzero(states.valid[states.index(object_id)])[0]
    if valid.size == 0:
        return []
    picks = np.unique(np.round(np.linspace(0, valid.size - 1, min(count, valid.size))).astype(np.int64))
    return [int(states.frame_idx[valid[k]]) for k in picks]


def box_corners(states: AgentStates, object_id: str, step: int, margin: float = 0.0) -> np.ndarray:
    """``[8, 3]`` world corners (``geometry.box_corners`` order) of ``object_id`` 's box at ``step``, grown by
    ``margin`` metres on every side."""
    row = states.index(object_id)
    center = np.array([*states.xy[row, step], states.z[row, step]])
    return geometry.box_corners(center, states.size[row] + 2.0 * margin, float(states.heading[row, step]))


def look_renders(graph: SceneGraph, log: SceneLog, states: AgentStates, object_ids: Sequence[str],
                 frames: Sequence[int]) -> list[FrameRender]:
    """Renders of ``graph`` at ``frames`` from the log's cameras that see a box of ``object_ids`` (frames no camera
    sees them in are skipped): the look check's views, at a third of the cost of every camera."""
    step_of = {int(f): k for k, f in enumerate(states.frame_idx)}
    out = []
    for frame in frames:
        step = step_of[int(frame)]
        rows = [o for o in object_ids if states.valid[states.index(o), step]]
        if not rows:
            continue
        boxes = [box_corners(states, o, step, BOX_MARGIN_M) for o in rows]
        views = [v for v in frame_views(log, int(frame)) if any(
            geometry.project_box_bounds(box, v.K, v.cam_to_world, v.width, v.height) is not None for box in boxes)]
        if views:
            out.append(render_frame(graph, int(frame), views))
    return out


def node_crops(renders: Sequence[FrameRender], node_id: int, object_id: str, category: str,
               box_size: Sequence[float], min_pixels: int = MIN_LOOK_PIXELS) -> list[ObjectCrop]:
    """Crops of the pixels whose top node is ``node_id``, in every rendered view with ``min_pixels`` of them."""
    out = []
    for frame in renders:
        if frame.node_id is None:
            raise ValueError(f"frame {frame.frame_idx} was rendered without node ids")
        for c, camera in enumerate(frame.cameras):
            mask = frame.node_id[c] == node_id
            if int(mask.sum()) < min_pixels:
                continue
            cut = crop_object(frame.rgb[c], mask)
            if cut is not None:
                rgb, m, bbox = cut
                out.append(ObjectCrop(rgb, m, category, np.asarray(box_size, np.float64), frame.frame_idx, camera,
                                      object_id, bbox))
    return out


def _read(crops: Sequence[ObjectCrop], wanted: str, gain: float = 1.0) -> tuple[str, float, list[str]]:
    """``(main colour of the track, share of the crops' area whose own main colour is wanted, each crop's main
    colour)`` under ``gain``; every crop is described once."""
    if gain != 1.0:
        crops = [dataclasses.replace(c, rgb=np.clip(c.rgb * gain, 0.0, 1.0).astype(np.float32)) for c in crops]
    subtype = subtype_from_size(crops[0].category, np.median([c.box_size for c in crops], axis=0))
    views = [describe_object(c.rgb, c.mask, c.category, c.box_size, subtype) for c in crops]
    names = [v.colors[0] for v in views]
    area = np.array([c.area for c in crops], dtype=np.float64)
    hits = np.array([name == wanted for name in names])
    return describe_track(crops, views=views).colors[0], float(area[hits].sum() / max(area.sum(), 1.0)), names


def exposure_gain(crops: Sequence[ObjectCrop], wanted: str) -> tuple[str, float]:
    """``(colour the crops read as, gain)`` (module docstring): gain ``1.0`` when they already read as ``wanted``
    in ``LOOK_SHARE`` of their area, else the first gain on the ladder that makes them, else the gain under
    which the most area reads as ``wanted`` with the track reading so too, else ``1.0``. ``wanted`` and the
    read colour must both be achromatic for a gain (a gain that darkens a blue reading partly black makes it
    read black).

    Raises:
        ValueError: no crops.
    """
    if not crops:
        raise ValueError("exposure_gain needs at least one crop")
    seen, share, names = _read(crops, wanted)
    if (seen == wanted and share >= LOOK_SHARE) or seen not in ACHROMATIC_NAMES or wanted not in ACHROMATIC_NAMES:
        return seen, 1.0
    # the track reads right but parts of it do not: lighter if most of the rest reads darker
    off = _main_other(crops, names, wanted) if seen == wanted else seen
    lighter = ACHROMATIC_NAMES.index(wanted) > ACHROMATIC_NAMES.index(off)
    ladder = BRIGHTER_GAINS if lighter else DARKER_GAINS
    best = (share if seen == wanted else -1.0, 1.0)
    for gain in ladder:
        track, part, _ = _read(crops, wanted, gain)
        if track == wanted and part >= LOOK_SHARE:
            return seen, gain
        if track == wanted and part > best[0]:
            best = (part, gain)
    return seen, best[1]


def _main_other(crops: Sequence[ObjectCrop], names: Sequence[str], wanted: str) -> str:
    """The achromatic name the crops that do not read as ``wanted`` mostly read as (by area; ``names``: each
    crop's main colour)."""
    votes: dict[str, float] = {}
    for c, name in zip(crops, names):
        if name != wanted and name in ACHROMATIC_NAMES:
            votes[name] = votes.get(name, 0.0) + c.area
    return max(votes, key=votes.__getitem__) if votes else wanted


def match_exposure(log: SceneLog, graph: SceneGraph, delta: EditDelta, wanted: Mapping[int, str],
                   states: AgentStates, asset_of: Callable[[str], Asset], build: Callable[[EditDelta], SceneGraph]
                   ) -> tuple[EditDelta, SceneGraph, list[LookNote]]:
    """The delta and graph with each added node of ``wanted`` (node id -> asked colour) switched to the exposure
    variant that makes it read as that colour, and a note per checked node (module docstring).

    A gain picked on the crops is verified on a render of the variant (scaling a crop also brightens the
    background blended into its edge pixels; the render does not): one that does not read right yet moves
    one step further along its ladder, for at most ``VERIFY_ROUNDS`` renders.

    Args:
        log: the sequence's log (cameras).
        graph: the edited graph (``delta`` applied).
        delta: the edit's delta.
        wanted: added node id -> asked colour; other colours and unknown nodes are skipped.
        states: the edited agent states (where each added object exists).
        asset_of: asset id -> asset (the draft's assets).
        build: the edited graph of a delta (variants resolvable).
    """
    added = {a.node_id: a for a in delta.added}
    checks = {n: c for n, c in wanted.items()
              if n in added and c in COLOR_NAMES and added[n].category in CHECKED_CATEGORIES}
    if not checks or not log.images:  # nothing asked, or no cameras to look through (a log without images)
        return delta, graph, []
    frames = sorted({f for n in checks for f in look_frames(states, added[n].object_id)})
    objects = [added[n].object_id for n in checks]
    renders = look_renders(graph, log, states, objects, frames)
    notes: dict[int, LookNote] = {}
    gains: dict[int, float] = {}
    for node_id, color in sorted(checks.items()):
        crops = _crops(renders, added[node_id], asset_of)
        seen, gain = exposure_gain(crops, color) if crops else (None, 1.0)
        notes[node_id] = LookNote(node_id, color, seen, gain, verified=seen == color, final=seen)
        if gain != 1.0:
            gains[node_id] = gain
    out_delta, out_graph = delta, graph
    for _ in range(VERIFY_ROUNDS):
        if not gains:
            break
        out_delta = dataclasses.replace(delta, added=tuple(_with_gain(a, gains[a.node_id]) if a.node_id in gains
                                                           else a for a in delta.added))
        out_graph = build(out_delta)
        renders = look_renders(out_graph, log, states, objects, frames)
        unsure: dict[int, float] = {}
        for node_id, gain in gains.items():
            variant = next(a for a in out_delta.added if a.node_id == node_id)
            track, share, _ = _read(_crops(renders, variant, asset_of), checks[node_id])
            ok = track == checks[node_id] and share >= LOOK_SHARE
            notes[node_id] = dataclasses.replace(notes[node_id], gain=gain, verified=ok, final=track)
            further = _next_gain(gain)
            if not ok and further is not None:
                unsure[node_id] = further
        if not unsure:
            break
        gains = {**gains, **unsure}
    for note in notes.values():
        logger.info("look check: %s", note.describe())
    return out_delta, out_graph, list(notes.values())


def _crops(renders: Sequence[FrameRender], node: AddedNode, asset_of: Callable[[str], Asset]) -> list[ObjectCrop]:
    asset = asset_of(node.asset_id)
    return node_crops(renders, node.node_id, node.object_id, asset.category, asset.size)


def _next_gain(gain: float) -> float | None:
    """The gain one step further from 1 on ``gain`` 's ladder (``None`` at its end)."""
    ladder = BRIGHTER_GAINS if gain > 1.0 else DARKER_GAINS
    return next((g for g in ladder if abs(g - 1.0) > abs(gain - 1.0) + 1e-9), None)


def _with_gain(added: AddedNode, gain: float) -> AddedNode:
    return dataclasses.replace(added, asset_id=f"{added.asset_id}{VARIANT_SEP}{exposure_suffix(gain)}")


__all__ = ["BOX_MARGIN_M", "BRIGHTER_GAINS", "CHECKED_CATEGORIES", "DARKER_GAINS", "LOOK_FRAMES", "LOOK_SHARE",
           "MIN_LOOK_PIXELS", "VERIFY_ROUNDS", "LookNote", "box_corners", "exposure_gain", "look_frames",
           "look_renders", "match_exposure", "node_crops"]
