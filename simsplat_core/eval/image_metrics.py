"""Image quality metrics (torch): PSNR, SSIM, their masked variants and the D-SSIM training loss.

Images are float tensors in ``[0, 1]`` laid out channels-last, ``[H, W, 3]`` or batched ``[B, H, W, 3]``
(any channel count works). Conventions:

* **PSNR** ``= 10 log10(1 / MSE)`` per image (data range 1). Batched inputs give one value per image.
* **SSIM** (Wang et al. 2004) with an 11x11 Gaussian window (sigma 1.5), ``C1 = 0.01^2``,
  ``C2 = 0.03^2``, statistics per channel. ``padding="valid"`` (the metric default) evaluates the map only
  where the window fits inside the image, i.e. an ``[H - 10, W - 10]`` map, as scikit-image's
  ``structural_similarity(gaussian_weights=True, sigma=1.5, use_sample_covariance=False)`` does.
  ``padding="same"`` zero-pads (the 3DGS training convention) so every pixel gets a value.
* **Masked PSNR**: MSE over the masked pixels only (all channels). **Masked SSIM**: mean of the
  ``"same"``-padded SSIM map over the masked pixels (the window still sees unmasked neighbours, which
  is what "SSIM of the object region" means in driving-scene papers). Both return ``nan`` for an
  empty mask.
* **D-SSIM** loss ``= 1 - SSIM`` (``"same"`` padding, mean over the map).
"""

from __future__ import annotations

import math
from typing import Literal

import torch
import torch.nn.functional as F
from torch import Tensor

SSIM_WINDOW = 11
SSIM_SIGMA = 1.5
SSIM_C1 = 0.01**2
SSIM_C2 = 0.03**2

Padding = Literal["valid", "same"]


def _batched(x: Tensor) -> Tensor:
    """``[H, W, C]`` or ``[B, H, W, C]`` -> ``[B, H, W, C]``."""
    if x.dim() == 3:
        return x[None]
    if x.dim() != 4:
        raise ValueError(f"expected an image [H, W, C] or a batch [B, H, W, C], got shape {list(x.shape)}")
    return x


def _check_pair(pred: Tensor, target: Tensor) -> tuple[Tensor, Tensor]:
    if pred.shape != target.shape:
        raise ValueError(f"pred and target shapes differ: {list(pred.shape)} vs {list(target.shape)}")
    return _batched(pred), _batched(target)


def mse(pred: Tensor, target: Tensor) -> Tensor:
    """Mean squared error per image: ``[H, W, C]`` -> ``[]``, ``[B, H, W, C]`` -> ``[B]``."""
    squeeze = pred.dim() == 3
    p, t = _check_pair(pred, target)
    out = (p - t).square().mean(dim=(1, 2, 3))
    return out[0] if squeeze else out


def psnr_from_mse(value: Tensor | float) -> Tensor:
    """``10 log10(1 / mse)`` (data range 1); ``inf`` for a zero MSE."""
    value = torch.as_tensor(value, dtype=torch.float64)
    return -10.0 * torch.log10(value)


def psnr(pred: Tensor, target: Tensor) -> Tensor:
    """PSNR in dB per image (data range 1): ``[H, W, C]`` -> ``[]``, ``[B, H, W, C]`` -> ``[B]``."""
    return psnr_from_mse(mse(pred.double(), target.double()))


def gaussian_window(size: int = SSIM_WINDOW, sigma: float = SSIM_SIGMA, dtype: torch.dtype = torch.float32,
                    device: torch.device | str = "cpu") -> Tensor:
    """Normalised 1D Gaussian window ``[size]`` (the 2D window is its outer product)."""
    coords = torch.arange(size, dtype=torch.float64) - (size - 1) / 2.0
    g = torch.exp(-(coords**2) / (2.0 * sigma**2))
    return (g / g.sum()).to(dtype=dtype, device=device)


def _filter(x: Tensor, window: Tensor, padding: Padding) -> Tensor:
    """Separable Gaussian filter of ``[B, C, H, W]`` per channel (``"valid"`` shrinks by ``size - 1``)."""
    channels, size = x.shape[1], window.shape[0]
    pad = size // 2 if padding == "same" else 0
    wx = window.view(1, 1, 1, size).expand(channels, 1, 1, size)
    wy = window.view(1, 1, size, 1).expand(channels, 1, size, 1)
    x = F.conv2d(x, wx, padding=(0, pad), groups=channels)
    return F.conv2d(x, wy, padding=(pad, 0), groups=channels)


def ssim_map(pred: Tensor, target: Tensor, padding: Padding = "valid", window_size: int = SSIM_WINDOW,
             sigma: float = SSIM_SIGMA) -> Tensor:
    """Per-pixel SSIM averaged over channels.

    Args:
        pred, target: ``[H, W, C]`` or ``[B, H, W, C]`` in ``[0, 1]``.
        padding: ``"valid"`` -> map ``[B, H - size + 1, W - size + 1]``; ``"same"`` -> ``[B, H, W]``.

    Returns:
        ``[B, H', W']`` (``B = 1`` for a single image).
    """
    if padding not in ("valid", "same"):
        raise ValueError(f"padding must be 'valid' or 'same', got {padding!r}")
    p, t = _check_pair(pred, target)
    if padding == "valid" and min(p.shape[1], p.shape[2]) < window_size:
        raise ValueError(f"image {p.shape[1]}x{p.shape[2]} is smaller than the SSIM window {window_size}")
    x = p.permute(0, 3, 1, 2)  # [B, C, H, W]
    y = t.permute(0, 3, 1, 2)
    window = gaussian_window(window_size, sigma, x.dtype, x.device)
    stacked = torch.cat([x, y, x * x, y * y, x * y], dim=1)  # [B, 5C, H, W]
    stats = _filter(stacked, window, padding)
    mu_x, mu_y, e_xx, e_yy, e_xy = stats.chunk(5, dim=1)
    var_x = e_xx - mu_x * mu_x
    var_y = e_yy - mu_y * mu_y
    cov = e_xy - mu_x * mu_y
    num = (2 * mu_x * mu_y + SSIM_C1) * (2 * cov + SSIM_C2)
    den = (mu_x * mu_x + mu_y * mu_y + SSIM_C1) * (var_x + var_y + SSIM_C2)
    return (num / den).mean(dim=1)  # [B, H', W']


def ssim(pred: Tensor, target: Tensor, padding: Padding = "valid") -> Tensor:
    """Mean SSIM per image: ``[H, W, C]`` -> ``[]``, ``[B, H, W, C]`` -> ``[B]``."""
    squeeze = pred.dim() == 3
    out = ssim_map(pred, target, padding).mean(dim=(1, 2))
    return out[0] if squeeze else out


def dssim_loss(pred: Tensor, target: Tensor) -> Tensor:
    """Training loss ``1 - SSIM`` (``"same"`` padding, mean over the batch and pixels), a scalar."""
    return 1.0 - ssim_map(pred, target, padding="same").mean()


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
    p, t = _check_pair(pred.double(), target.double())
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
    m = _mask_batched(mask, _batched(pred).shape).to(smap.dtype)
    count = m.sum(dim=(1, 2))
    out = torch.where(count > 0, (smap * m).sum(dim=(1, 2)) / count.clamp(min=1), torch.full_like(count, math.nan))
    return out[0] if squeeze else out


__all__ = [
    "dssim_loss",
    "gaussian_window",
    "masked_psnr",
    "masked_ssim",
    "mse",
    "psnr",
    "psnr_from_mse",
    "ssim",
    "ssim_map",
]
