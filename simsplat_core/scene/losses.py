"""Training losses of the reconstruction (and the SSIM kernel they share with ``scene.image_metrics``).

Images are float tensors in ``[0, 1]`` laid out channels-last, ``[H, W, C]`` or batched ``[B, H, W, C]``.

* **SSIM map** (Wang et al. 2004): 11x11 Gaussian window (sigma 1.5), ``C1 = 0.01^2``, ``C2 = 0.03^2``,
  statistics per channel, averaged over channels. ``padding="valid"`` evaluates the map only where the
  window fits inside the image (``[H - 10, W - 10]``, scikit-image's convention); ``padding="same"``
  zero-pads (the 3DGS training convention) so every pixel gets a value.
* **D-SSIM** loss ``= 1 - SSIM`` (``"same"`` padding, mean over the batch and pixels).
* ``valid_mean``: the mean over the valid pixels of a ``[B, H, W]`` validity mask (every pixel when ``None``);
  the photometric losses take the same mask, so masked pixels (e.g. the ego car's body) never pull.
* ``psnr_from_mse``: ``10 log10(1 / MSE)`` (data range 1), the trainer's running figure.

These live with the trainer that minimises them; :mod:`simsplat_core.scene.image_metrics` builds the
held-out image metrics on top of the same kernel.
"""

from __future__ import annotations

from typing import Literal

import torch
import torch.nn.functional as F
from torch import Tensor

SSIM_WINDOW = 11
SSIM_SIGMA = 1.5
SSIM_C1 = 0.01**2
SSIM_C2 = 0.03**2

Padding = Literal["valid", "same"]


def batched(x: Tensor) -> Tensor:
    """``[H, W, C]`` or ``[B, H, W, C]`` -> ``[B, H, W, C]``."""
    if x.dim() == 3:
        return x[None]
    if x.dim() != 4:
        raise ValueError(f"expected an image [H, W, C] or a batch [B, H, W, C], got shape {list(x.shape)}")
    return x


def check_pair(pred: Tensor, target: Tensor) -> tuple[Tensor, Tensor]:
    """Both images batched (``[B, H, W, C]``) after checking that their shapes agree."""
    if pred.shape != target.shape:
        raise ValueError(f"pred and target shapes differ: {list(pred.shape)} vs {list(target.shape)}")
    return batched(pred), batched(target)


def psnr_from_mse(value: Tensor | float) -> Tensor:
    """``10 log10(1 / mse)`` (data range 1); ``inf`` for a zero MSE."""
    value = torch.as_tensor(value, dtype=torch.float64)
    return -10.0 * torch.log10(value)


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
    p, t = check_pair(pred, target)
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


def valid_mean(values: Tensor, valid: Tensor | None) -> Tensor:
    """Mean of ``values`` (``[B, H, W]`` or ``[B, H, W, C]``) over the pixels where ``valid`` (``[B, H, W]`` bool)
    holds, over every pixel when ``valid`` is ``None``; 0 when no pixel is valid (a scalar)."""
    if valid is None:
        return values.mean()
    weight = valid.to(values.dtype)
    if values.dim() == weight.dim() + 1:
        weight = weight[..., None].expand_as(values)
    return (values * weight).sum() / weight.sum().clamp(min=1.0)


def dssim_loss(pred: Tensor, target: Tensor, valid: Tensor | None = None) -> Tensor:
    """Training loss ``1 - SSIM`` (``"same"`` padding, mean over the batch and the ``valid`` pixels), a scalar."""
    smap = ssim_map(pred, target, padding="same")  # [B, H, W]
    return 1.0 - valid_mean(smap, None if valid is None else valid.reshape(smap.shape))


__all__ = [
    "SSIM_C1",
    "SSIM_C2",
    "SSIM_SIGMA",
    "SSIM_WINDOW",
    "Padding",
    "batched",
    "check_pair",
    "dssim_loss",
    "gaussian_window",
    "psnr_from_mse",
    "valid_mean",
    "ssim_map",
]
