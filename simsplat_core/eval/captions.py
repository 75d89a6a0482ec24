"""Captioner accuracy against a log's ground-truth attributes (the synthetic world's, or any log that
stores ``ObjectInfo.attributes`` ``color`` / ``upper_color`` / ``lower_color`` / ``subtype``).

Two granularities: per *view* (one crop: object x frame x camera with at least ``min_area`` mask
pixels) and per *object* (``describe_track`` over all of its views). Colours must match exactly
(no synonyms); for pedestrians "colour" means both clothing colours. The world calls every person
subtype ``"pedestrian"``; its people are 1.55-1.92 m tall, so that reads as ``"adult"``.
"""

from __future__ import annotations

import logging
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field

from simsplat_core.language.appearance.captioner import AppearanceCaption, AppearanceCaptioner, Captioner
from simsplat_core.language.appearance.colors import UNKNOWN
from simsplat_core.language.appearance.crops import ObjectCrop, crops_from_log
from simsplat_core.types import ObjectInfo, SceneLog

logger = logging.getLogger(__name__)

#: Ground-truth subtype names that the captioner spells differently.
SUBTYPE_ALIASES = {"pedestrian": "adult"}


@dataclass
class Tally:
    """Counts of one category: views/objects judged, how many got a colour at all (not ``"unknown"``),
    and how many had the right colour / subtype."""

    n: int = 0
    decided: int = 0
    color_ok: int = 0
    subtype_ok: int = 0
    upper_ok: int = 0
    lower_ok: int = 0
    confusions: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    by_color: dict[str, list[int]] = field(default_factory=lambda: defaultdict(lambda: [0, 0]))

    def add(self, truth: ObjectInfo, caption: AppearanceCaption) -> None:
        attrs = truth.attributes
        self.n += 1
        self.decided += UNKNOWN not in caption.colors[:2]
        expected = attrs.get("subtype", "")
        self.subtype_ok += caption.subtype == SUBTYPE_ALIASES.get(expected, expected)
        if truth.category == "pedestrian":
            up = caption.upper_color == attrs.get("upper_color")
            low = caption.lower_color == attrs.get("lower_color")
            self.upper_ok += up
            self.lower_ok += low
            self.color_ok += up and low
            got = f"{caption.upper_color}/{caption.lower_color}"
            want = f"{attrs.get('upper_color')}/{attrs.get('lower_color')}"
        else:
            got, want = caption.color, attrs.get("color", "")
            self.color_ok += got == want
            self.by_color[want][0] += 1
            self.by_color[want][1] += got == want
        if got != want:
            self.confusions[f"{want}->{got}"] += 1

    def merge(self, other: Tally) -> None:
        self.n += other.n
        self.decided += other.decided
        self.color_ok += other.color_ok
        self.subtype_ok += other.subtype_ok
        self.upper_ok += other.upper_ok
        self.lower_ok += other.lower_ok
        for k, v in other.confusions.items():
            self.confusions[k] += v
        for k, (n, ok) in other.by_color.items():
            self.by_color[k][0] += n
            self.by_color[k][1] += ok

    def summary(self, pedestrian: bool = False) -> dict:
        """Rates (``None`` when nothing was judged) plus counts and the most common confusions.

        ``color_acc`` counts ``"unknown"`` as wrong; ``coverage`` is the share with a colour and
        ``color_acc_decided`` the accuracy among those; ``recall_by_color`` maps each true colour to
        ``[correct, total]`` (not for pedestrians)."""
        rate = (lambda k: round(k / self.n, 4)) if self.n else (lambda k: None)
        out = {
            "n": self.n,
            "color_acc": rate(self.color_ok),
            "coverage": rate(self.decided),
            "color_acc_decided": round(self.color_ok / self.decided, 4) if self.decided else None,
            "subtype_acc": rate(self.subtype_ok),
        }
        if pedestrian:
            out.update(upper_acc=rate(self.upper_ok), lower_acc=rate(self.lower_ok))
        else:
            out["recall_by_color"] = {c: [ok, n] for c, (n, ok) in sorted(self.by_color.items())}
        out["top_confusions"] = dict(sorted(self.confusions.items(), key=lambda kv: -kv[1])[:5])
        return out


@dataclass
class CaptionAccuracy:
    """Per-category tallies over views and over objects."""

    views: dict[str, Tally] = field(default_factory=lambda: defaultdict(Tally))
    objects: dict[str, Tally] = field(default_factory=lambda: defaultdict(Tally))

    def merge(self, other: CaptionAccuracy) -> None:
        for mine, theirs in ((self.views, other.views), (self.objects, other.objects)):
            for cat, tally in theirs.items():
                mine[cat].merge(tally)

    def summary(self) -> dict:
        return {
            level: {cat: t.summary(cat == "pedestrian") for cat, t in sorted(tallies.items())}
            for level, tallies in (("views", self.views), ("objects", self.objects))
        }


def evaluate_crops(
    log: SceneLog, crops: Sequence[ObjectCrop], captioner: AppearanceCaptioner | None = None
) -> CaptionAccuracy:
    """Judge ``captioner`` (default ``Captioner()``) on ``crops`` of ``log`` against its attributes."""
    judged: AppearanceCaptioner = captioner or Captioner()
    result = CaptionAccuracy()
    by_object: dict[str, list[ObjectCrop]] = defaultdict(list)
    for crop in crops:
        truth = log.object(crop.object_id)
        result.views[truth.category].add(truth, judged.describe(crop))
        by_object[crop.object_id].append(crop)
    for object_id, views in by_object.items():
        truth = log.object(object_id)
        result.objects[truth.category].add(truth, judged.describe_track(views))
    return result


def evaluate_log(log: SceneLog, min_area: int = 100, captioner: AppearanceCaptioner | None = None) -> CaptionAccuracy:
    """``evaluate_crops`` over every view of ``log`` with at least ``min_area`` mask pixels."""
    return evaluate_crops(log, crops_from_log(log, min_area=min_area), captioner)
