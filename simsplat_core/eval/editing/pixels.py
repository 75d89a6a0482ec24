"""Pixel checks of edits: visible where it should be, looks as asked, gone when removed.

Inputs are :class:`~simsplat_core.eval.editing.observation.PixelEvidence`: the edited Gaussian scene's
renders with node ids, the world's own rendering of the same edit with instance ids and the log's images
of the unedited scene, at the same frames and cameras.

* **visible**: an inserted, moved or redrawn object should be seen where the world's rendering of the
  edit shows it mostly unoccluded (at least ``MIN_VIEW_PIXELS`` pixels of its instance in a view, and at
  least ``MIN_UNOCCLUDED`` of the pixels its silhouette would cover with nothing in front of it: a sliver
  past a nearer car is a place where the reconstructed neighbour's extent decides, not the edit), at frames
  where the ego replaying its log touches no agent (``PixelEvidence.ego_contact``); there the
  rendered node must cover at least ``MIN_COVER`` of those pixels, in at least ``MIN_VIEW_SHARE`` of the
  views (a node pixel within ``EDGE_TOLERANCE_PX`` of a world pixel covers it). An object the world does not
  show in the checked frames (out of view, hidden behind others) has
  nothing to check in pixels (its place is checked on the trajectories).
* **appearance**: the built-in captioner (``language.appearance.captioner.describe_track``) captions the
  rendered crops of an inserted or replacing object the world shows (views with at least
  ``MIN_CAPTION_PIXELS`` node pixels, box size from the edited agent; an object drawn smaller than that
  everywhere is not judged by colour); its colour (vehicles, static objects:
  main or second colour; pedestrians: top and trousers) must be the asked one -- or what the captioner says
  of the world's own rendering of an object of the asked colour at the same place
  (``PixelEvidence.reference_captions``: the captioner's lighting confusions, e.g. a sunlit silver body named
  white, are no editing error) -- and the body style (vehicles, cones and barriers: the captioner names them
  from the box) the asked one.
* **removed**: in views where the log shows a removed object (``MIN_VIEW_PIXELS``), the edited render has
  no pixel of its node, and over the object's pixels it is closer (mean squared error) to the world's
  rendering without the object than to the log's image with it, in views holding at least ``MIN_VIEW_SHARE``
  of the judged pixels (a view weighs by its pixels: 45 pixels of a car at the horizon are noise beside 2,000
  of it up close).
  Where the world without it shows the background on ``MIN_BACKGROUND_SHARE`` of those pixels, only those
  count: an agent the removed one hid all along (a black car that only ever showed behind a silver one)
  is a grey smear in any reconstruction, and that smear is not the removed car (``removed_region``).
"""

from __future__ import annotations

import numpy as np

from simsplat_core.eval.editing.checks import CheckResult, Verdict
from simsplat_core.eval.editing.intents import EditIntent
from simsplat_core.eval.editing.observation import EditObservation, PixelEvidence, ViewSet, state_changes
from simsplat_core.language.appearance.captioner import describe_track
from simsplat_core.language.appearance.crops import ObjectCrop, crop_object
from simsplat_core.language.appearance.subtypes import STATIC_SUBTYPES, VEHICLE_SUBTYPES

#: A view shows an object when it has at least this many of its pixels.
MIN_VIEW_PIXELS = 40
#: ... and at least this share of its unoccluded silhouette (``PixelEvidence.world_silhouette``).
MIN_UNOCCLUDED = 0.5
#: The rendered node must cover this share of the world's pixels of the object in a view.
MIN_COVER = 0.3
#: A world pixel counts as covered when the node is drawn within this many pixels of it: a reconstruction's edge
#: may sit a pixel off the world's mesh, which decides a far car 11 x 5 pixels large.
EDGE_TOLERANCE_PX = 1
#: ... in this share of the views that show it.
MIN_VIEW_SHARE = 0.6
#: A removal is judged over the pixels where the world without it shows the background when they are at
#: least this share of the object's pixels (``removed_region``).
MIN_BACKGROUND_SHARE = 0.3
#: Crops smaller than this are not captioned.
MIN_CAPTION_PIXELS = 40
#: Body styles the captioner names from the box (others are not checked by type).
CHECKABLE_SUBTYPES: frozenset[str] = frozenset(VEHICLE_SUBTYPES) | frozenset(STATIC_SUBTYPES[:2])


def grown(mask: np.ndarray, radius: int) -> np.ndarray:
    """``mask`` (``[H, W]`` bool) grown by ``radius`` pixels (square neighbourhood)."""
    if radius <= 0:
        return mask
    h, w = mask.shape
    padded = np.pad(mask, radius)
    out = np.zeros_like(mask)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            out |= padded[dy:dy + h, dx:dx + w]
    return out


def expected_views(evidence: PixelEvidence, object_id: str) -> list[tuple[int, int]]:
    """``(frame row, camera)`` where the world's rendering of the edit shows ``object_id``, mostly unoccluded
    when its silhouette is known."""
    inst = evidence.world_instance.get(object_id)
    if inst is None:
        return []
    counts = (evidence.world_edited.ids == inst).sum(axis=(2, 3))  # [F, C]
    shown = counts >= MIN_VIEW_PIXELS
    shown &= np.array([f not in evidence.ego_contact for f in evidence.world_edited.frames])[:, None]
    silhouette = evidence.world_silhouette.get(object_id)
    if silhouette is not None:
        shown &= counts >= MIN_UNOCCLUDED * silhouette
    return [(int(f), int(c)) for f, c in zip(*np.nonzero(shown))]


def check_visible(evidence: PixelEvidence, object_id: str, node_id: int, v: Verdict) -> bool:
    """``object_id`` drawn by ``node_id`` covers the world's pixels of it in enough views (module docstring).

    Returns whether the world shows the object at all in the checked frames (an object it does not show -- out
    of view or hidden behind others -- has nothing to be checked in pixels; where it is, the state checks say).
    """
    views = expected_views(evidence, object_id)
    if not views:
        v.note(f"{object_id} not mostly in sight in the checked frames (out of view or hidden)")
        return False
    inst = evidence.world_instance[object_id]
    covered = []
    for f, c in views:
        truth = evidence.world_edited.ids[f, c] == inst
        drawn = grown(evidence.edited.ids[f, c] == node_id, EDGE_TOLERANCE_PX)
        covered.append(float((truth & drawn).sum()) / float(truth.sum()))
    share = float(np.mean(np.asarray(covered) >= MIN_COVER))
    v.measured[f"visible_share_{object_id}"] = share
    v.require(share >= MIN_VIEW_SHARE, f"{object_id} drawn in {share:.0%} of the {len(views)} views where it should "
              f"be seen (median cover {np.median(covered):.0%})")
    return True


def object_crops(views: ViewSet, id_value: int, object_id: str, category: str,
                 box_size: np.ndarray) -> list[ObjectCrop]:
    """Crops of the pixels with id ``id_value`` in every view of ``views`` that has at least
    ``MIN_CAPTION_PIXELS`` of them."""
    out = []
    for f in range(len(views.frames)):
        for c, camera in enumerate(views.cameras):
            mask = views.ids[f, c] == id_value
            if mask.sum() < MIN_CAPTION_PIXELS:
                continue
            cut = crop_object(views.rgb[f, c], mask)
            if cut is None:
                continue
            rgb, m, bbox = cut
            out.append(ObjectCrop(rgb, m, category, np.asarray(box_size, np.float64), views.frames[f], camera,
                                  object_id, bbox))
    return out


def check_appearance(evidence: PixelEvidence, intent: EditIntent, object_id: str, node_id: int, category: str,
                     box_size: np.ndarray, v: Verdict) -> None:
    """The captioner's description of the rendered object matches the asked colours and body style."""
    asset = intent.asset
    if asset is None:
        return
    crops = object_crops(evidence.edited, node_id, object_id, category, box_size)
    if not crops:  # drawn where it should be (``check_visible``), but too small anywhere for the captioner
        v.note(f"{object_id} too small to caption (no view with {MIN_CAPTION_PIXELS}+ pixels)")
        return
    caption = describe_track(crops)
    reference = evidence.reference_captions.get(object_id)
    v.note(f"{object_id} captioned {caption.text!r}"
           + (f" (the asked look renders as {reference.text!r})" if reference is not None else ""))
    if category == "pedestrian":
        for part, asked, got, ref in (
                ("top", asset.upper, caption.upper_color, reference.upper_color if reference else None),
                ("trousers", asset.lower, caption.lower_color, reference.lower_color if reference else None)):
            if asked is not None:
                v.require(got in (asked, ref), f"{object_id}: {part} {got}, asked {asked}"
                          + (f" (renders as {ref})" if ref not in (None, asked) else ""))
        return
    if asset.color is not None:
        ref_colors = reference.colors if reference is not None else ()
        v.require(asset.color in caption.colors or (bool(ref_colors) and caption.colors[:1] == ref_colors[:1]),
                  f"{object_id}: colour {'/'.join(caption.colors)}, asked {asset.color}"
                  + (f" (renders as {'/'.join(ref_colors)})" if ref_colors and ref_colors[0] != asset.color else ""))
    if asset.subtype is not None and asset.subtype in CHECKABLE_SUBTYPES:
        v.require(caption.subtype == asset.subtype, f"{object_id}: a {caption.subtype}, asked a {asset.subtype}")


def removed_region(shown: np.ndarray, ids_without: np.ndarray) -> np.ndarray:
    """The pixels where a removal is judged by colour: of ``shown`` (``[H, W]`` bool, where the log showed the
    removed object), those where the world without it shows the background (``ids_without`` ``[H, W]``
    instance ids, ``0`` = background) -- when they are at least ``MIN_BACKGROUND_SHARE`` of them; otherwise
    all of ``shown``. An agent that the removed one hid from the log all along is unknown to any
    reconstruction; what is judged is that the removed object is gone from the static scene behind it."""
    background = shown & (ids_without == 0)
    return background if background.sum() >= MIN_BACKGROUND_SHARE * shown.sum() else shown


def check_removed(evidence: PixelEvidence, object_id: str, node_id: int, v: Verdict) -> None:
    """No pixel of the removed node, and its region looks like the world without it (module docstring)."""
    inst = evidence.original_instance.get(object_id)
    if inst is None:
        v.require(False, f"{object_id} has no instance id in the log")
        return
    orig = evidence.world_original
    counts = (orig.ids == inst).sum(axis=(2, 3))
    views = [(int(f), int(c)) for f, c in zip(*np.nonzero(counts >= MIN_VIEW_PIXELS))]
    if not views:
        v.note(f"{object_id} not mostly in sight in the checked frames (out of view or hidden)")
        return
    left = int(sum(int((evidence.edited.ids[f, c] == node_id).sum()) for f, c in views))
    v.require(left == 0, f"{left} pixels of removed node {node_id} still rendered")
    closer, weight = [], []
    for f, c in views:
        mask = removed_region(orig.ids[f, c] == inst, evidence.world_edited.ids[f, c])
        edited = evidence.edited.rgb[f, c][mask]
        without = float(np.mean((edited - evidence.world_edited.rgb[f, c][mask]) ** 2))
        with_it = float(np.mean((edited - orig.rgb[f, c][mask]) ** 2))
        closer.append(without < with_it)
        weight.append(float(mask.sum()))
    share = float(np.average(closer, weights=weight))
    v.measured[f"removed_share_{object_id}"] = share
    v.require(share >= MIN_VIEW_SHARE, f"where {object_id} was, the render looks like the scene with it in "
              f"{1 - share:.0%} of its pixels over {len(views)} views")


def check_pixels(intent: EditIntent, obs: EditObservation, evidence: PixelEvidence) -> CheckResult:
    """Every pixel check that applies to the edit (module docstring)."""
    v = Verdict()
    before, after = obs.before, obs.after
    if before is None or after is None:
        return CheckResult(False, f"refused ({obs.refused}): {obs.message}")
    changes = state_changes(before, after)
    for object_id in changes.removed:
        check_removed(evidence, object_id, int(before.node_ids[before.index(object_id)]), v)
    shown = set(changes.added) | set(changes.moved) | set(changes.redrawn)
    for object_id in after.object_ids:
        if object_id not in shown:
            continue
        row = after.index(object_id)
        node = int(after.node_ids[row])
        if not v.require(node >= 0, f"{object_id} has no scene-graph node after the edit"):
            continue
        seen = check_visible(evidence, object_id, node, v)
        if seen and (object_id in changes.added or object_id in changes.redrawn):
            check_appearance(evidence, intent, object_id, node, after.categories[row], after.size[row], v)
    return v.result()


__all__ = ["CHECKABLE_SUBTYPES", "EDGE_TOLERANCE_PX", "MIN_BACKGROUND_SHARE", "MIN_CAPTION_PIXELS", "MIN_COVER",
           "MIN_UNOCCLUDED", "MIN_VIEW_PIXELS", "MIN_VIEW_SHARE", "check_appearance", "check_pixels", "check_removed",
           "check_visible", "expected_views", "grown", "object_crops", "removed_region"]
