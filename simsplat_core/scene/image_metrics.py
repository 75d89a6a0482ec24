"""Image quality metrics of reconstructions (torch): PSNR, SSIM and their masked variants.

Images are float tensors in ``[0, 1]`` laid out channels-last, ``[H, W, 3]`` or batched ``[B, H, W, 3]``
(any channel count works). Conventions:

* **PSNR** ``= 10 log10(1 / MSE)`` per image (data range 1). Batched inputs give one value per image.
* **SSIM**: the kernel of :mod:`simsplat_core.scene.losses` (its window, constants and padding modes);
  ``padding="valid"`` by default here, as scikit-image's ``structural_similarity(gaussian_weights=True,
  sigma=1.5, use_sample_covariance=False)`` evaluates it.
* **Masked PSNR**: MSE over the masked pixels only (all channels). **Masked SSIM**: mean of the
  ``"same"``-padded SSIM map over the masked pixels (the window still sees unmasked neighbours, which
  is what "SSIM of the object region" means in driving-scene papers). Both return ``nan`` for an
  empty mask.

These score a reconstruction on held-out frames (:mod:`simsplat_core.scene.evaluate`, run by the trainer
at checkpoints and at the end): validation belongs to the method it validates, so they live in
``scene/`` beside the losses, and the evaluation package ``eval/`` stays on top of the algorithms.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from simsplat_core.scene.losses import Padding, batched, check_pair, psnr_from_mse, ssim_map


def mse(pred: Tensor, target: Tensor) -> Tensor:
    """Mean squared error per image: ``[H, W, C]`` -> ``[]``, ``[B, H, W, C]`` -> ``[B]``."""
    squeeze = pred.dim() == 3
    p, t = check_pair(pred, target)
    out = (p - t).square().mean(dim=(1, 2, 3))
    return out[0] if squeeze else out


def psnr(pred: Tensor, target: Tensor) -> Tensor:
    """PSNR in dB per image (data range 1): ``[H, W, C]`` -> ``[]``, ``[B, H, W, C]`` -> ``[B]``."""
    return psnr_from_mse(mse(pred.double(), target.double()))


def ssim(pred: Tensor, target: Tensor, padding: Padding = "valid") -> Tensor:
    """Mean SSIM per image: ``[H, W, C]`` -> ``[]``, ``[B, H, W, C]`` -> ``[B]``."""
    squeeze = pred.dim() == 3
    out = ssim_map(pred, target, padding).mean(dim=(1, 2))
    return out[0] if squeeze else out


def _mask_batched(mask: Tensor, shape: torch.Size) -> Tensor:
    mask = mask if mask.dim() == 3 else mask[None]
    if tuple(mask.shape) != tuple(shape[:3]):
        raise ValueError(f"mask shape {list(mask.shape)} does not match images {list(shape[:3])}")
    return mask.bool()


def masked_psnr(pred: Tensor, target: Tensor, mask: Tensor) -> Tensor:
    """PSNR over the pixels where ``mask`` (``[H, W]`` / ``[B, H, W]`` bool) is true; ``nan`` when empty.

    Returns ``[]`` for a single image, ``[B]`` for a batch.
    """
    squeeze = pred.dim() == 3
    p, t = check_pair(pred.double(), target.double())
    m = _mask_batched(mask, p.shape)
    count = m.sum(dim=(1, 2)) * p.shape[-1]  # [B]
    sq = ((p - t).square() * m[..., None]).sum(dim=(1, 2, 3))
    out = torch.where(count > 0, psnr_from_mse(sq / count.clamp(min=1)), torch.full_like(sq, math.nan))
    return out[0] if squeeze else out


def masked_ssim(pred: Tensor, target: Tensor, mask: Tensor) -> Tensor:
    """Mean of the ``"same"``-padded SSIM map over the masked pixels; ``nan`` when the mask is empty.

    Returns ``[]`` for a single image, ``[B]`` for a batch.
    """
    squeeze = pred.dim() == 3
    smap = ssim_map(pred, target, padding="same")  # [B, H, W]
    m = _mask_batched(mask, batched(pred).shape).to(smap.dtype)
    count = m.sum(dim=(1, 2))
    out = torch.where(count > 0, (smap * m).sum(dim=(1, 2)) / count.clamp(min=1), torch.full_like(count, math.nan))
    return out[0] if squeeze else out


__all__ = ["masked_psnr", "masked_ssim", "mse", "psnr", "ssim"]
