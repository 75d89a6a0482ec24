"""The built-in appearance captioner: subtype from the box, colours from the masked pixels, a short caption.

    cap = describe_object(rgb, mask, "vehicle", (4.85, 1.95, 1.78))
    cap.text        # "a red SUV"
    describe_track(crops).text   # one caption per object, votes over its frames

Colours come from ``colors.py`` (vehicle body colour ignoring glass and tyres, clothing colours of
pedestrians from the upper and lower body, the dominant colour of street furniture), the subtype from
``subtypes.py`` unless a hint (e.g. a dataset's class) is given. Several frames of one object are
aggregated by a vote of colour names weighted by mask area, so one badly lit or occluded view does
not decide.

Caption templates (``caption_text``):

* vehicles, cyclists, signs, static objects: ``"a red SUV"``, ``"a red stop sign"``,
  ``"an orange traffic cone"``, ``"an orange and white barrier"`` (static objects name a second
  colour when it covers at least ``SECOND_COLOR_FRACTION`` of the pixels);
* pedestrians: ``"a pedestrian in a red top and blue trousers"`` (``"a child in ..."`` for children).
"""

from __future__ import annotations

import logging
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from simsplat_core.color_names import COLOR_NAMES
from simsplat_core.language.appearance.colors import (
    UNKNOWN,
    ColorEstimate,
    clothing_colors,
    dominant_color,
    vehicle_body_color,
)
from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.language.appearance.subtypes import (
    PEDESTRIAN_SUBTYPES,
    SIGN_SUBTYPES,
    STATIC_SUBTYPES,
    VEHICLE_SUBTYPES,
    refine_sign,
    subtype_from_size,
)

logger = logging.getLogger(__name__)

#: A static object's second colour enters the caption when its region holds this share of the pixels.
SECOND_COLOR_FRACTION = 0.25
#: Over several views, "silver" beats a "white" majority when silver views hold this share of the area.
#: The confusion is one-sided: a silver body whose visible faces are all sunlit looks white (about 30 %
#: of silver views in the synthetic world), while a white body never looks silver (ambient light is
#: the floor of its lightness; 1 of ~850 white views). Measured on held-out seeds this turns 7/12
#: silver cars right into 11/12 and keeps all 28 white ones.
SILVER_OVER_WHITE_SHARE = 0.1
_VEHICLE_LIKE = ("vehicle", "cyclist", "other")


@dataclass(frozen=True)
class AppearanceCaption:
    """What an object looks like.

    Attributes:
        text: the caption, e.g. ``"a red SUV"``.
        category: object category.
        subtype: e.g. ``"SUV"``, ``"adult"``, ``"traffic cone"``.
        colors: named colours, main first (pedestrians: upper, lower).
        upper_color, lower_color: clothing colours (pedestrians only, else ``None``).
        confidence: in ``[0, 1]``; one view: the naming margin of the weakest colour; several views:
            the vote share of the weakest winning colour.
    """

    text: str
    category: str
    subtype: str
    colors: tuple[str, ...]
    upper_color: str | None = None
    lower_color: str | None = None
    confidence: float = 0.0

    @property
    def color(self) -> str:
        """The main colour (upper-body colour for pedestrians)."""
        return self.colors[0] if self.colors else UNKNOWN


def article(phrase: str) -> str:
    """``"a"`` or ``"an"`` before ``phrase``; spoken initialisms count by their letter (``"an SUV"``)."""
    word = phrase.split(" ", 1)[0]
    if word.isupper() and len(word) > 1:
        return "an" if word[0] in "AEFHILMNORSX" else "a"
    return "an" if word[:1].lower() in "aeiou" else "a"


def _with_article(phrase: str) -> str:
    return f"{article(phrase)} {phrase}"


def caption_text(
    category: str, subtype: str, colors: Sequence[str], upper: str | None = None, lower: str | None = None
) -> str:
    """The caption of an object from its parts (unknown colours are left out)."""
    if category == "pedestrian":
        person = "child" if subtype == "child" else "pedestrian"
        parts = []
        if upper and upper != UNKNOWN:
            parts.append(f"{article(upper)} {upper} top")
        if lower and lower != UNKNOWN:
            parts.append(f"{lower} trousers")
        return _with_article(person) + (" in " + " and ".join(parts) if parts else "")
    known = [c for c in colors if c != UNKNOWN]
    return _with_article(" ".join([" and ".join(known[:2]), subtype] if known else [subtype]))


def _static_colors(estimate: ColorEstimate) -> tuple[str, ...]:
    second = [r.name for r in estimate.regions if r.name != estimate.name and r.fraction >= SECOND_COLOR_FRACTION]
    return (estimate.name, *second[:1])


def describe_object(
    rgb: np.ndarray,
    mask: np.ndarray,
    category: str,
    box_size,
    subtype_hint: str | None = None,
) -> AppearanceCaption:
    """Describe one view of an object.

    Args:
        rgb: ``[H, W, 3]`` float32 display RGB in ``[0, 1]``.
        mask: ``[H, W]`` bool, the object's pixels.
        category: object category (``types.CATEGORIES``).
        box_size: ``[3]`` box ``(length, width, height)`` in metres.
        subtype_hint: a known subtype (e.g. from track metadata); overrides the size rule.
    """
    subtype = subtype_hint or subtype_from_size(category, box_size)
    if category == "pedestrian":
        upper, lower = clothing_colors(rgb, mask)
        return AppearanceCaption(
            caption_text(category, subtype, (), upper.name, lower.name),
            category,
            subtype,
            (upper.name, lower.name),
            upper.name,
            lower.name,
            min(upper.confidence, lower.confidence),
        )
    if category in _VEHICLE_LIKE:
        estimate = vehicle_body_color(rgb, mask)
        colors: tuple[str, ...] = (estimate.name,)
    else:
        # a sign is a panel on a pole: two materials; cones, barriers and the like are one
        estimate = dominant_color(rgb, mask, one_neutral_material=category != "sign")
        colors = _static_colors(estimate) if category == "static" else (estimate.name,)
        if subtype_hint is None:
            subtype = refine_sign(subtype, estimate.name)
    return AppearanceCaption(
        caption_text(category, subtype, colors), category, subtype, colors, confidence=estimate.confidence
    )


def _vote(weights: dict[str, float]) -> tuple[str, float]:
    """Winner of an area-weighted vote and its share (ties: the name first in ``COLOR_NAMES``).
    ``"unknown"`` views abstain."""
    weights = {n: w for n, w in weights.items() if n != UNKNOWN}
    total = sum(weights.values())
    if total <= 0:
        return UNKNOWN, 0.0
    rank = {name: i for i, name in enumerate(COLOR_NAMES)}
    name = min(weights, key=lambda n: (-weights[n], rank.get(n, len(rank))))
    return name, weights[name] / total


def describe_track(crops: Sequence[ObjectCrop], subtype_hint: str | None = None,
                   views: Sequence[AppearanceCaption] | None = None) -> AppearanceCaption:
    """One caption for an object seen in several crops (frames and cameras).

    Every crop is described by ``describe_object`` (``views``: those descriptions, already made, one per crop,
    with the same ``subtype_hint``); each colour slot (main and second colour, or
    upper and lower clothing) is decided by a vote of the crops' names weighted by mask area, except
    that silver wins over white with ``SILVER_OVER_WHITE_SHARE`` of the area; the subtype comes from
    the hint or the median box size (then, for signs, the voted colour).

    Raises:
        ValueError: no crops, or crops of different objects.
    """
    if not crops:
        raise ValueError("describe_track needs at least one crop")
    ids = {c.object_id for c in crops}
    if len(ids) > 1:
        raise ValueError(f"describe_track got crops of several objects: {sorted(ids)[:5]}")
    category = crops[0].category
    box = np.median(np.stack([np.asarray(c.box_size, dtype=np.float64) for c in crops]), axis=0)
    subtype = subtype_hint or subtype_from_size(category, box)
    if views is not None and len(views) != len(crops):
        raise ValueError(f"describe_track got {len(views)} views for {len(crops)} crops")
    slots: list[dict[str, float]] = [defaultdict(float), defaultdict(float)]
    for k, crop in enumerate(crops):
        cap = views[k] if views is not None else describe_object(crop.rgb, crop.mask, category, crop.box_size,
                                                                 subtype_hint or subtype)
        for slot, name in zip(slots, cap.colors):
            slot[name] += crop.area
    first, share1 = _vote(slots[0])
    if category == "pedestrian":
        lower, share2 = _vote(slots[1])
        return AppearanceCaption(
            caption_text(category, subtype, (), first, lower),
            category,
            subtype,
            (first, lower),
            first,
            lower,
            min(share1, share2),
        )
    known = sum(w for name, w in slots[0].items() if name != UNKNOWN)
    if first == "white" and slots[0].get("silver", 0.0) >= SILVER_OVER_WHITE_SHARE * known:
        first, share1 = "silver", slots[0]["silver"] / known
    if subtype_hint is None:
        subtype = refine_sign(subtype, first)
    colors: tuple[str, ...] = (first,)
    total = sum(c.area for c in crops)
    second, _ = _vote(slots[1])
    if second != UNKNOWN and second != first and slots[1][second] >= 0.5 * total:
        colors = (first, second)
    return AppearanceCaption(caption_text(category, subtype, colors), category, subtype, colors, confidence=share1)


@runtime_checkable
class AppearanceCaptioner(Protocol):
    """Anything that captions object crops (the built-in ``Captioner``, a VLM client, ...)."""

    @property
    def name(self) -> str:
        """Identifies the captioner in content keys."""
        ...

    def describe(self, crop: ObjectCrop) -> AppearanceCaption:
        """Caption of one crop."""
        ...

    def describe_track(self, crops: Sequence[ObjectCrop]) -> AppearanceCaption:
        """One caption for several crops of one object."""
        ...


@dataclass(frozen=True)
class Captioner:
    """The built-in rule-based captioner (``describe_object`` / ``describe_track``).

    Attributes:
        subtype_hints: optional ``object_id -> subtype`` overrides (e.g. dataset classes).
    """

    subtype_hints: dict[str, str] | None = None
    name: str = "rule-captioner/1"

    def _hint(self, object_id: str) -> str | None:
        return (self.subtype_hints or {}).get(object_id)

    def describe(self, crop: ObjectCrop) -> AppearanceCaption:
        return describe_object(crop.rgb, crop.mask, crop.category, crop.box_size, self._hint(crop.object_id))

    def describe_track(self, crops: Sequence[ObjectCrop]) -> AppearanceCaption:
        return describe_track(crops, self._hint(crops[0].object_id) if crops else None)


def appearance_vocabulary(colors: Sequence[str] = COLOR_NAMES) -> list[str]:
    """Caption-style phrases for every subtype and colour (and pedestrian clothing colours).

    These are the texts an appearance query is likely to resemble; an autoencoder trained on them
    next to a scene's features keeps those regions of the text space decodable.
    """
    phrases = []
    for subtype in VEHICLE_SUBTYPES + STATIC_SUBTYPES[:2] + SIGN_SUBTYPES[:3]:
        phrases.append(caption_text("vehicle", subtype, ()))
        phrases += [caption_text("vehicle", subtype, (c,)) for c in colors]
    for person in PEDESTRIAN_SUBTYPES:
        phrases.append(caption_text("pedestrian", person, ()))
        phrases += [caption_text("pedestrian", person, (), upper=c) for c in colors]
        phrases += [caption_text("pedestrian", person, (), lower=c) for c in colors]
    return list(dict.fromkeys(phrases))
