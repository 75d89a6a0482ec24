"""Edit fidelity against ground truth: the edited Gaussian renders against the world's rendering of the edit.

No published editor can measure this: a synthetic world re-renders the very edit the editor made
(``world_edit.py``) -- the object removed, the object driving its new trajectory, a world-native object
inserted -- so the edited renders have a reference image.

Per edit, over the views (frames x cameras) compared:

* ``psnr`` / ``ssim``: mean over views of the full-image PSNR / SSIM (``scene.image_metrics``) of the
  edited render against the world's rendering of the edited scene;
* ``psnr_region``: PSNR pooled over the *edit region* -- the pixels where the world's renderings of the
  edited and of the unedited scene differ in colour -- i.e. what the edit changed;
* ``psnr_unedited_region``: the unedited scene's render against the log's image over the same region,
  the reconstruction's own quality there (the fair bar for ``psnr_region``).

The unedited scene's test PSNR (:func:`render_fidelity` of the unedited render against the log's images at
the test frames) is what the table puts next to them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.eval.editing.observation import ViewSet
from simsplat_core.scene.image_metrics import psnr, ssim

#: Colour difference (max over channels) above which a pixel belongs to the edit region.
REGION_TOL = 2.0 / 255.0


@dataclass(frozen=True)
class FidelityScore:
    """Fidelity of one edit (module docstring); ``nan`` where a value has no pixels."""

    psnr: float
    ssim: float
    psnr_region: float
    psnr_unedited_region: float
    views: int
    region_pixels: int


def _tensor(x: np.ndarray) -> torch.Tensor:
    return torch.as_tensor(np.ascontiguousarray(x), dtype=torch.float32)


def render_fidelity(rendered: ViewSet, reference: ViewSet) -> tuple[float, float]:
    """``(mean PSNR, mean SSIM)`` over the views of two view sets of the same frames and cameras."""
    _same_views(rendered, reference)
    pred = _tensor(rendered.rgb.reshape(-1, *rendered.rgb.shape[2:]))
    ref = _tensor(reference.rgb.reshape(-1, *reference.rgb.shape[2:]))
    return float(psnr(pred, ref).mean()), float(ssim(pred, ref).mean())


def edit_region(world_edited: ViewSet, world_original: ViewSet) -> np.ndarray:
    """``[F, C, H, W]`` bool: pixels whose colour the edit changes in the world's renders (the world renders
    deterministically, so every change of the scene -- an object, its shadow -- changes colours)."""
    _same_views(world_edited, world_original)
    return np.asarray(np.abs(world_edited.rgb - world_original.rgb).max(axis=-1) > REGION_TOL, dtype=bool)


def _pooled(pred: np.ndarray, target: np.ndarray, mask: np.ndarray) -> float:
    """PSNR of the mean squared error over every masked pixel of every view."""
    sq = ((pred.astype(np.float64) - target.astype(np.float64)) ** 2)[mask]
    mse = float(sq.mean())
    return math.inf if mse == 0 else 10.0 * math.log10(1.0 / mse)


def edit_fidelity(edited: ViewSet, world_edited: ViewSet, world_original: ViewSet,
                  unedited: ViewSet | None = None) -> FidelityScore:
    """Fidelity of one edit over the views the three (four) view sets share (module docstring).

    Args:
        edited: the edited Gaussian scene's renders.
        world_edited: the world's rendering of the edit.
        world_original: the log's images (the world's rendering of the unedited scene).
        unedited: the unedited Gaussian scene's renders, for ``psnr_unedited_region``.
    """
    p, s = render_fidelity(edited, world_edited)
    region = edit_region(world_edited, world_original)
    psnr_region = _pooled(edited.rgb, world_edited.rgb, region) if region.any() else math.nan
    base = math.nan
    if unedited is not None and region.any():
        _same_views(unedited, world_original)
        base = _pooled(unedited.rgb, world_original.rgb, region)
    return FidelityScore(p, s, psnr_region, base, len(edited.frames) * len(edited.cameras), int(region.sum()))


def _same_views(a: ViewSet, b: ViewSet) -> None:
    if a.frames != b.frames or a.cameras != b.cameras or a.rgb.shape != b.rgb.shape:
        raise ValueError(f"view sets differ: frames {a.frames} / {b.frames}, cameras {a.cameras} / {b.cameras}, "
                         f"images {a.rgb.shape} / {b.rgb.shape}")


__all__ = ["REGION_TOL", "FidelityScore", "edit_fidelity", "edit_region", "render_fidelity"]
