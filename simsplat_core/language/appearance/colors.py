"""Colour names of masked image regions, robust to shading.

Everything works in CIELAB (OpenCV's float conversion: ``L`` in ``[0, 100]``, ``a, b`` roughly in
``[-128, 127]``). Lambert shading multiplies a surface's RGB by a factor (in the synthetic world
0.64 on vertical faces turned away from the sun up to 1.2 on faces lit head-on), which in Lab
scales ``L + 16``, ``a`` and ``b`` by nearly the same amount. So the **chromaticity**
``(a, b) / (L + 16)`` is (nearly) shading-invariant and names chromatic colours on its own; its
norm, the saturation ``s = C / (L + 16)``, separates achromatic pixels (``s < ACHROMATIC_S``) from
coloured ones, orange (``s`` ~1.05) from brown (~0.6), yellow (~0.8) from beige (~0.3) and red
(~1.4) from pink (~0.5).

Achromatic colours differ only in lightness, which shading changes: a white body in shadow is as
dark as a lit silver one. They are named from the *least-lit* part of the surface
(``SHADOW_PERCENTILE`` of the grey pixels' lightness; see ``region_colors``), whose light is the
ambient sky light shared by every object of a scene, on the scale of ``AchromaticScale``. What
stays ambiguous is a silver car whose every visible face is sunlit: it shows the lightness of a
white car in shade and is called white. (Using the windows as a grey card, via the body-to-window
lightness ratio, was tried and dropped: the ratios of white and silver bodies overlap enough that it
mislabelled more white cars than it recovered silver ones.)

Region naming: the masked pixels (eroded by one pixel so edges do not bleed in) are clustered by a
deterministic k-means in Lab; each cluster is named from its median; clusters with the same name
merge into one ``ColorRegion``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import cv2
import numpy as np

from simsplat_core.color_names import ACHROMATIC_NAMES, CHROMATIC_PALETTE

logger = logging.getLogger(__name__)

#: Below this saturation ``C / (L + 16)`` a pixel or region is achromatic (silver ~0.05, gray ~0.06,
#: vehicle glass ~0.25, beige ~0.28).
ACHROMATIC_S = 0.16
#: Regions darker than this (``L``) are black whatever their chromaticity (chroma is noise there).
BLACK_L = 14.0
#: Percentile of the lightness of a neutral surface's grey pixels that names it (its least-lit part).
SHADOW_PERCENTILE = 10.0
#: The name given when a surface's colour cannot be told (no usable pixels).
UNKNOWN = "unknown"


@dataclass(frozen=True)
class AchromaticScale:
    """Thresholds of the shadow lightness (``L`` of a surface's least-lit part) between achromatic names.

    A neutral surface of display value ``v`` shows ``L(0.64 v)`` on faces in ambient light only:
    about 60 for white (0.9), 46 for silver (0.66), 28 for gray (0.4) and 4 for black (0.05); lit
    faces are brighter, up to ``L(1.2 v)``. The thresholds sit between the ambient levels, nearer
    the upper one, since the least-lit part of a surface is sometimes still partly lit.

    Attributes:
        gray_from: ``L`` at or above which a region is gray rather than black.
        silver_from: ``L`` at or above which it is silver (``None``: no silver on this scale, e.g.
            clothing, where people do not say "silver"; gray then runs up to ``white_from``).
        white_from: ``L`` at or above which it is white.
    """

    gray_from: float = 16.0
    silver_from: float | None = 44.0
    white_from: float = 58.0

    def name(self, lightness: float) -> str:
        if lightness < self.gray_from:
            return "black"
        if lightness >= self.white_from:
            return "white"
        if self.silver_from is not None and lightness >= self.silver_from:
            return "silver"
        return "gray"

    def margin(self, lightness: float) -> float:
        """Distance in ``L`` to the nearest threshold, scaled to ``[0, 1]`` (10 L units = 1)."""
        edges = [e for e in (self.gray_from, self.silver_from, self.white_from) if e is not None]
        return float(np.clip(min(abs(lightness - e) for e in edges) / 10.0, 0.0, 1.0))


VEHICLE_SCALE = AchromaticScale()
CLOTHING_SCALE = AchromaticScale(gray_from=16.0, silver_from=None, white_from=52.0)

def rgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB of display RGB: ``[..., 3]`` float in ``[0, 1]`` -> ``[..., 3]`` float32 (``L`` 0..100)."""
    rgb = np.clip(np.asarray(rgb, dtype=np.float32), 0.0, 1.0)
    if rgb.size == 0:
        return np.zeros(rgb.shape, dtype=np.float32)
    flat = np.ascontiguousarray(rgb.reshape(-1, 1, 3))
    return cv2.cvtColor(flat, cv2.COLOR_RGB2Lab).reshape(rgb.shape)


def chromaticity(lab: np.ndarray) -> np.ndarray:
    """Shading-invariant chromaticity ``(a, b) / (L + 16)``: ``[..., 3]`` -> ``[..., 2]``."""
    lab = np.asarray(lab, dtype=np.float32)
    return lab[..., 1:] / (lab[..., :1] + 16.0)


def saturation(lab: np.ndarray) -> np.ndarray:
    """``C / (L + 16)``: ``[..., 3]`` -> ``[...]``."""
    return np.linalg.norm(chromaticity(lab), axis=-1)


def glass_mask(lab: np.ndarray) -> np.ndarray:
    """Vehicle-glass-like colours: dark (``L`` 12..40), weakly saturated (``s`` 0.16..0.45), bluish
    (hue 220..320 deg). ``[..., 3]`` -> ``[...]`` bool."""
    lab = np.asarray(lab, dtype=np.float32)
    chroma = chromaticity(lab)
    sat = np.linalg.norm(chroma, axis=-1)
    hue = np.degrees(np.arctan2(chroma[..., 1], chroma[..., 0])) % 360.0
    light = lab[..., 0]
    return (light >= 12.0) & (light <= 40.0) & (sat >= ACHROMATIC_S) & (sat <= 0.45) & (hue >= 220.0) & (hue <= 320.0)


def shadow_lightness(lab_pixels: np.ndarray) -> float:
    """``SHADOW_PERCENTILE`` of the lightness of ``[N, 3]`` pixels (their least-lit part; ``N > 0``)."""
    return float(np.percentile(np.asarray(lab_pixels)[:, 0], SHADOW_PERCENTILE))


def _reference_chromaticities() -> np.ndarray:
    lab = rgb_to_lab(np.array([c.rgb for c in CHROMATIC_PALETTE], dtype=np.float32))
    return chromaticity(lab)  # [P, 2]


_CHROMA_REFS = _reference_chromaticities()


@dataclass(frozen=True)
class ColorDecision:
    """A colour name with a confidence in ``[0, 1]`` (1 = unambiguous)."""

    name: str
    confidence: float


def name_lab(lab: np.ndarray, scale: AchromaticScale = VEHICLE_SCALE) -> ColorDecision:
    """Name one colour given as Lab ``[3]`` (for a region: its median).

    Rules, in order: ``L < BLACK_L`` -> black; saturation ``< ACHROMATIC_S`` -> the achromatic
    ``scale``; otherwise the chromatic palette entry with the nearest chromaticity, unless neutral
    (chromaticity 0) is nearer still (a greyish tint such as bluish glass is achromatic).
    """
    lab = np.asarray(lab, dtype=np.float32).reshape(3)
    lightness = float(lab[0])
    if lightness < BLACK_L:
        return ColorDecision("black", float(np.clip((BLACK_L - lightness) / 10.0, 0.0, 1.0)))
    chroma = chromaticity(lab)
    sat = float(np.linalg.norm(chroma))
    if sat >= ACHROMATIC_S:
        dist = np.linalg.norm(_CHROMA_REFS - chroma[None], axis=1)  # [P]
        order = np.argsort(dist)
        d1, d2 = float(dist[order[0]]), float(dist[order[1]])
        if d1 < sat:
            return ColorDecision(CHROMATIC_PALETTE[int(order[0])].name, float(1.0 - d1 / max(min(d2, sat), 1e-6)))
    return ColorDecision(scale.name(lightness), scale.margin(lightness))


def erode_mask(mask: np.ndarray, pixels: int = 1, keep_fraction: float = 0.35, min_pixels: int = 12) -> np.ndarray:
    """``[H, W]`` bool mask eroded by ``pixels`` (3x3 cross), unless that leaves fewer than
    ``keep_fraction`` of its pixels or ``min_pixels`` (thin or tiny masks are returned unchanged)."""
    mask = np.asarray(mask, dtype=bool)
    if pixels <= 0 or not mask.any():
        return mask
    kernel = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    eroded = cv2.erode(mask.astype(np.uint8), kernel, iterations=pixels).astype(bool)
    kept = int(eroded.sum())
    if kept < min_pixels or kept < keep_fraction * int(mask.sum()):
        return mask
    return eroded


def masked_lab(rgb: np.ndarray, mask: np.ndarray, erode: int = 1) -> np.ndarray:
    """Lab of the pixels under the (eroded) mask: ``rgb [H, W, 3]``, ``mask [H, W]`` -> ``[N, 3]``."""
    inner = erode_mask(mask, erode)
    return rgb_to_lab(np.asarray(rgb, dtype=np.float32)[inner])


def kmeans(x: np.ndarray, k: int, iterations: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """Deterministic Lloyd k-means.

    Centres start at the points of rank ``(i + 0.5) / k`` along the first coordinate (lightness for
    Lab), so the result depends only on the data.

    Args:
        x: ``[N, C]`` float points.
        k: number of clusters (reduced to ``N`` when there are fewer points).
    Returns:
        labels ``[N]`` int64 in ``[0, k')`` and centres ``[k', C]`` (empty clusters dropped, labels
        renumbered).
    """
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, x.shape[1]))
    k = max(1, min(k, n))
    order = np.argsort(x[:, 0], kind="stable")
    centres = x[order[((np.arange(k) + 0.5) * n / k).astype(int)]].copy()  # [k, C]
    labels = np.zeros(n, dtype=np.int64)
    for it in range(iterations):
        d = ((x[:, None, :] - centres[None]) ** 2).sum(-1)  # [N, k]
        new = d.argmin(axis=1)
        if it > 0 and np.array_equal(new, labels):
            break
        labels = new
        for j in range(k):
            sel = labels == j
            if sel.any():
                centres[j] = x[sel].mean(axis=0)
    used = np.unique(labels)
    remap = np.full(k, -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return remap[labels], centres[used]


@dataclass(frozen=True)
class ColorRegion:
    """Pixels of one colour name within a mask.

    Attributes:
        name: colour name.
        fraction: share of the analysed pixels.
        lab: ``[3]`` median Lab of the region's largest cluster.
        lightness: the ``L`` the name was decided on (shadow lightness for white/silver/gray,
            else the median).
        confidence: naming confidence.
        glass_like: the region looks like vehicle glass (``glass_mask`` of its median).
    """

    name: str
    fraction: float
    lab: tuple[float, float, float]
    lightness: float
    confidence: float
    glass_like: bool = False


def region_colors(
    lab_pixels: np.ndarray, k: int = 3, scale: AchromaticScale = VEHICLE_SCALE, one_neutral_material: bool = True
) -> list[ColorRegion]:
    """Cluster ``[N, 3]`` Lab pixels into ``k`` clusters, name each, merge clusters of equal name
    (glass-like clusters stay apart from opaque ones of the same name).

    A cluster is named from its median Lab (``name_lab``). Achromatic clusters other than black and
    glass are then renamed from the shadow lightness of their grey pixels (a few coloured pixels,
    e.g. tail lights, may share a cluster): the least-lit part, usually a face in ambient light only,
    whose level is the same for every object of a scene while lit faces vary with the sun's
    direction. With ``one_neutral_material`` (a vehicle body) those clusters are named *together*,
    so the shaded and the lit faces of one white body both count as white; without it (a sign panel
    on a grey pole) each cluster is named from its own pixels.

    Returns:
        regions sorted by decreasing fraction.
    """
    lab_pixels = np.asarray(lab_pixels, dtype=np.float32).reshape(-1, 3)
    n = lab_pixels.shape[0]
    if n == 0:
        return []
    labels, _ = kmeans(lab_pixels, k)
    clusters = []  # [name, pixels, median, lightness, confidence, glass_like]
    for j in range(int(labels.max()) + 1):
        px = lab_pixels[labels == j]
        med = np.median(px, axis=0)
        decision = name_lab(med, scale)
        clusters.append([decision.name, px, med, float(med[0]), decision.confidence, bool(glass_mask(med))])
    neutral = [c for c in clusters if c[0] in ACHROMATIC_NAMES and c[0] != "black" and not c[5]]
    groups = [neutral] if one_neutral_material else [[c] for c in neutral]
    for group in (g for g in groups if g):
        px = np.concatenate([c[1] for c in group])
        grey = px[(px[:, 0] >= BLACK_L) & (saturation(px) < ACHROMATIC_S)]
        lightness = shadow_lightness(grey if len(grey) else px)
        name = scale.name(max(lightness, scale.gray_from))
        for c in group:
            c[0], c[3], c[4] = name, lightness, scale.margin(lightness)
    merged: dict[tuple[str, bool], ColorRegion] = {}
    for name, px, med, lightness, conf, glass in sorted(clusters, key=lambda c: -c[1].shape[0]):
        frac = px.shape[0] / n
        key = (name, glass)
        if key in merged:
            r = merged[key]
            merged[key] = ColorRegion(name, r.fraction + frac, r.lab, r.lightness, r.confidence, glass)
        else:
            lab = (float(med[0]), float(med[1]), float(med[2]))
            merged[key] = ColorRegion(name, frac, lab, lightness, float(conf), glass)
    return sorted(merged.values(), key=lambda r: -r.fraction)


@dataclass(frozen=True)
class ColorEstimate:
    """The colour chosen for a surface, with the regions it was chosen from.

    Attributes:
        name: the colour name (``UNKNOWN`` when it cannot be told).
        confidence: naming confidence in ``[0, 1]``.
        regions: all named regions of the analysed pixels, largest first.
        pixels: number of pixels analysed.
    """

    name: str
    confidence: float
    regions: tuple[ColorRegion, ...]
    pixels: int

    @property
    def names(self) -> list[str]:
        """Region names, largest first."""
        return [r.name for r in self.regions]


#: A vehicle body region must hold at least this share of the masked pixels.
MIN_BODY_FRACTION = 0.12
def vehicle_body_color(rgb: np.ndarray, mask: np.ndarray, k: int = 3) -> ColorEstimate:
    """Body colour of a vehicle: ``rgb [H, W, 3]`` in ``[0, 1]``, ``mask [H, W]`` bool.

    The masked pixels form ``k`` Lab clusters (body, glass, tyres/shadow for a typical car); the body
    is the largest region that is neither black (tyres, dark trim) nor glass-like and holds at least
    ``MIN_BODY_FRACTION`` of the pixels. When there is none the car is dark all over and black wins;
    when no opaque region is that large (only the windows show above an occluder, or a headlight)
    the colour is ``UNKNOWN``.
    """
    lab = masked_lab(rgb, mask)
    regions = region_colors(lab, k, VEHICLE_SCALE)
    opaque = [r for r in regions if not r.glass_like and r.fraction >= MIN_BODY_FRACTION]
    if not opaque:
        return ColorEstimate(UNKNOWN, 0.0, tuple(regions), lab.shape[0])
    body = [r for r in opaque if r.name != "black"]
    chosen = body[0] if body else opaque[0]
    return ColorEstimate(chosen.name, chosen.confidence, tuple(regions), lab.shape[0])


def dominant_color(
    rgb: np.ndarray,
    mask: np.ndarray,
    k: int = 3,
    prefer_chromatic: float = 0.2,
    one_neutral_material: bool = True,
) -> ColorEstimate:
    """Main colour of a generic object (cone, barrier, sign, unknown).

    The largest chromatic region wins when it holds at least ``prefer_chromatic`` of the pixels (an
    orange cone with a white band and a black base is orange; a stop sign on a grey pole is red);
    otherwise the largest region. ``one_neutral_material=False`` names neutral clusters separately
    (a sign: a white panel on a grey pole); see ``region_colors``.
    """
    lab = masked_lab(rgb, mask)
    regions = region_colors(lab, k, VEHICLE_SCALE, one_neutral_material)
    if not regions:
        return ColorEstimate(UNKNOWN, 0.0, (), 0)
    chromatic = [r for r in regions if r.name not in ACHROMATIC_NAMES and r.fraction >= prefer_chromatic]
    chosen = chromatic[0] if chromatic else regions[0]
    return ColorEstimate(chosen.name, chosen.confidence, tuple(regions), lab.shape[0])


#: Rows of a standing person's mask (fractions of its height, from the top) holding the top and the
#: trousers: below the head and neck (top ~19 %), above the hip band, above the shoes (bottom ~4 %).
UPPER_BAND = (0.2, 0.46)
LOWER_BAND = (0.6, 0.93)


def band_mask(mask: np.ndarray, band: tuple[float, float]) -> np.ndarray:
    """``mask [H, W]`` restricted to the rows ``band = (top, bottom)`` given as fractions of its own
    height (from its first to its last row)."""
    rows = np.nonzero(mask.any(axis=1))[0]
    out = np.zeros_like(mask, dtype=bool)
    if rows.size == 0:
        return out
    top, height = int(rows[0]), int(rows[-1]) - int(rows[0]) + 1
    r0 = top + int(np.floor(band[0] * height))
    r1 = top + max(int(np.ceil(band[1] * height)), int(np.floor(band[0] * height)) + 1)
    out[r0:r1] = mask[r0:r1]
    return out


def clothing_colors(rgb: np.ndarray, mask: np.ndarray, k: int = 2) -> tuple[ColorEstimate, ColorEstimate]:
    """Upper-body and lower-body colours of a pedestrian: ``rgb [H, W, 3]``, ``mask [H, W]`` bool.

    Each band (``UPPER_BAND`` / ``LOWER_BAND`` of the mask's height) is named by its largest region
    on the clothing scale (no "silver").
    """
    out = []
    for band in (UPPER_BAND, LOWER_BAND):
        lab = masked_lab(rgb, band_mask(mask, band))
        regions = region_colors(lab, k, CLOTHING_SCALE)
        if regions:
            out.append(ColorEstimate(regions[0].name, regions[0].confidence, tuple(regions), lab.shape[0]))
        else:
            out.append(ColorEstimate(UNKNOWN, 0.0, (), 0))
    return out[0], out[1]
