"""Recolouring an asset: the Gaussians of its body's dominant colour shifted to another named colour.

"Add a yellow taxi" in a bank without a yellow car: take the best car and repaint its body. The body
is found among the asset's Gaussians as the captioner finds it among pixels (``appearance.colors``):
the (opaque) Gaussians are clustered in Lab (deterministic k-means); each cluster is named from its
median (``name_lab``, glass-like clusters flagged by ``glass_mask``); the body is every non-glass cluster
named the asset's colour -- every non-glass achromatic cluster but black when that colour is achromatic
(lit and shaded faces of one white body get different grey names) -- or, when none is, the largest
non-black, non-glass cluster. For a pedestrian only the upper body (hips to neck) is searched: the
asset's colour is its top's.

An exposure variant (``exposed``) scales every Gaussian's colour (a pedestrian's: its upper body's) by one
gain: the same body seen under another scene's light (``editing.assets.look_check`` picks the gain that makes an
inserted object read as the asked achromatic colour where it is placed).

The shift keeps the shading: each body Gaussian's luminance relative to the body's median luminance
scales the target's display colour (``color_names.DISPLAY_RGB``), itself scaled by how the body's median
compares with the source colour's display value (the scene's exposure), both clipped to sane ranges.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from simsplat_core.color_names import ACHROMATIC_NAMES, COLOR_NAMES, DISPLAY_RGB
from simsplat_core.editing.assets.record import EXPOSED_FROM, RECOLOURED_FROM, VARIANT_SEP, Asset
from simsplat_core.language.appearance.captioner import caption_text
from simsplat_core.language.appearance.colors import (
    CLOTHING_SCALE,
    MIN_BODY_FRACTION,
    VEHICLE_SCALE,
    glass_mask,
    kmeans,
    name_lab,
    rgb_to_lab,
)
from simsplat_core.scene.gaussians import logit

#: Gaussians at least this opaque take part in finding the body (fainter ones follow their cluster's colour
#: only when they are body-coloured too: see ``body_rows``).
BODY_OPACITY = 0.3
#: Clusters of the body search.
BODY_CLUSTERS = 4
#: A pedestrian's upper body, as fractions of its height from the ground (hips to neck).
UPPER_BODY = (0.46, 0.88)
#: Clip ranges of the per-Gaussian shading factor and of the scene exposure.
SHADING_RANGE = (0.35, 1.8)
EXPOSURE_RANGE = (0.6, 1.4)
#: Gains an exposure variant may apply (``exposed``).
EXPOSURE_GAIN_RANGE = (0.5, 2.0)
#: Display RGB stays inside this range (logits stay finite).
RGB_RANGE = (0.004, 0.996)
#: Prefix of an exposure variant's id suffix: ``<asset_id>~exp1.20``.
EXPOSURE_TAG = "exp"
_LUMA = np.array([0.2126, 0.7152, 0.0722])


def _search_rows(asset: Asset) -> np.ndarray:
    """``[N]`` bool rows where the body is searched (upper body of a pedestrian, else everything)."""
    z = asset.gaussians.means[:, 2].numpy()
    if asset.category != "pedestrian":
        return np.ones(z.shape, dtype=bool)
    height = asset.size[2]
    ground = -height / 2.0
    return (z >= ground + UPPER_BODY[0] * height) & (z <= ground + UPPER_BODY[1] * height)


def body_rows(asset: Asset) -> np.ndarray:
    """``[N]`` bool: the Gaussians of the asset's body colour (see the module docstring).

    Raises:
        ValueError: the asset has no opaque Gaussian where its body would be.
    """
    rgb = asset.gaussians.rgb.numpy()
    lab = rgb_to_lab(rgb)  # [N, 3]
    search = _search_rows(asset)
    opaque = search & (asset.gaussians.opacities.numpy() >= BODY_OPACITY)
    if not opaque.any():
        raise ValueError(f"asset {asset.asset_id!r}: no opaque Gaussians to find its body colour in")
    labels, _ = kmeans(lab[opaque], BODY_CLUSTERS)
    scale = CLOTHING_SCALE if asset.category == "pedestrian" else VEHICLE_SCALE
    clusters = []  # (index, name, glass, fraction)
    for j in range(int(labels.max()) + 1):
        median = np.median(lab[opaque][labels == j], axis=0)
        clusters.append((j, name_lab(median, scale).name, bool(glass_mask(median)), float(np.mean(labels == j))))
    wanted = asset.color
    if wanted in ACHROMATIC_NAMES and wanted != "black":
        chosen = [j for j, name, glass, _ in clusters if not glass and name in ACHROMATIC_NAMES and name != "black"]
    else:
        chosen = [j for j, name, glass, _ in clusters if not glass and name == wanted]
    if not chosen:
        opaque_body = [c for c in clusters if not c[2] and c[1] != "black" and c[3] >= MIN_BODY_FRACTION]
        chosen = [max(opaque_body or clusters, key=lambda c: c[3])[0]]
    # every searched Gaussian (faint ones included) joins the cluster whose centre is nearest
    centres = np.stack([np.median(lab[opaque][labels == j], axis=0) for j in range(int(labels.max()) + 1)])
    nearest = np.argmin(((lab[:, None, :] - centres[None]) ** 2).sum(-1), axis=1)
    return search & np.isin(nearest, chosen)


def shifted_rgb(rgb: np.ndarray, source: str, target: str) -> np.ndarray:
    """``[M, 3]`` body colours ``rgb`` (display RGB of a ``source``-coloured surface) repainted ``target``,
    keeping each one's shading relative to their median (module docstring)."""
    luma = np.maximum(rgb @ _LUMA, 1e-4)
    median = float(np.median(luma))
    shading = np.clip(luma / max(median, 1e-4), *SHADING_RANGE)
    source_luma = float(np.asarray(DISPLAY_RGB.get(source, DISPLAY_RGB["gray"])) @ _LUMA)
    exposure = float(np.clip(median / max(source_luma, 1e-3), *EXPOSURE_RANGE))
    return np.clip(np.asarray(DISPLAY_RGB[target])[None] * (exposure * shading)[:, None], *RGB_RANGE)


def recolored(asset: Asset, color: str) -> Asset:
    """A variant of ``asset`` whose body is ``color`` (id ``<asset_id>~<color>``; ``attributes
    ["recoloured_from"]`` names the source; the caption names the new colour).

    Raises:
        ValueError: ``color`` is not a known colour name, or no body is found.
    """
    if color not in COLOR_NAMES:
        raise ValueError(f"unknown colour {color!r}; known: {list(COLOR_NAMES)}")
    rows = body_rows(asset)
    colors = asset.gaussians.colors.clone()  # logits: the rows off the body keep theirs bit for bit
    body_rgb = shifted_rgb(asset.gaussians.rgb.numpy()[rows], asset.color, color)
    colors[torch.as_tensor(rows)] = logit(torch.as_tensor(body_rgb, dtype=torch.float32))
    gs = asset.gaussians.map_rows(lambda name, t: colors if name == "colors" else t)
    if asset.category == "pedestrian":
        lower = asset.attributes.get("lower_color") or None
        caption = caption_text("pedestrian", asset.subtype, (), color, lower)
    else:
        caption = caption_text(asset.category, asset.subtype, (color,))
    return dataclasses.replace(asset, asset_id=f"{asset.asset_id}{VARIANT_SEP}{color}", caption=caption,
                               color=color, gaussians=gs,
                               attributes={**asset.attributes, RECOLOURED_FROM: asset.asset_id})


def exposure_suffix(gain: float) -> str:
    """The variant suffix of ``gain`` (two decimals: ``exp1.20``)."""
    return f"{EXPOSURE_TAG}{gain:.2f}"


def exposed(asset: Asset, gain: float) -> Asset:
    """A variant of ``asset`` with every Gaussian's display colour times ``gain`` (clipped to ``RGB_RANGE``;
    id ``<asset_id>~exp<gain>``, ``attributes["exposed_from"]`` names the source). A pedestrian's upper body
    (``UPPER_BODY``: its top, the colour it is asked and checked in) is scaled alone.

    Raises:
        ValueError: ``gain`` outside ``EXPOSURE_GAIN_RANGE``.
    """
    gain = round(float(gain), 2)
    if not EXPOSURE_GAIN_RANGE[0] <= gain <= EXPOSURE_GAIN_RANGE[1]:
        raise ValueError(f"exposure gain {gain} outside {EXPOSURE_GAIN_RANGE}")
    rgb = asset.gaussians.rgb
    rows = torch.as_tensor(_search_rows(asset)).unsqueeze(1)
    rgb = torch.where(rows, torch.clamp(rgb * gain, *RGB_RANGE), rgb)
    colors = logit(rgb.to(asset.gaussians.colors.dtype))
    gs = asset.gaussians.map_rows(lambda name, t: colors if name == "colors" else t)
    return dataclasses.replace(asset, asset_id=f"{asset.asset_id}{VARIANT_SEP}{exposure_suffix(gain)}", gaussians=gs,
                               attributes={**asset.attributes, EXPOSED_FROM: asset.asset_id})


__all__ = ["BODY_CLUSTERS", "EXPOSURE_GAIN_RANGE", "EXPOSURE_TAG", "UPPER_BODY", "body_rows", "exposed",
           "exposure_suffix", "recolored", "shifted_rgb"]
