"""Image metrics against known values and a slow per-window reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from simsplat_core.scene.image_metrics import masked_psnr, masked_ssim, psnr, ssim
from simsplat_core.scene.losses import SSIM_C1, SSIM_C2, dssim_loss, gaussian_window, ssim_map


def _images(seed: int = 0, shape: tuple[int, ...] = (24, 31, 3)) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    x = torch.rand(shape, generator=g, dtype=torch.float64)
    y = (x + 0.1 * torch.randn(shape, generator=g, dtype=torch.float64)).clamp(0, 1)
    return x, y


def _ssim_reference(x: np.ndarray, y: np.ndarray, size: int = 11, sigma: float = 1.5) -> np.ndarray:
    """Slow SSIM map ('valid' windows), one explicit weighted window per pixel and channel."""
    coords = np.arange(size) - (size - 1) / 2
    g = np.exp(-coords**2 / (2 * sigma**2))
    w = np.outer(g, g) / np.outer(g, g).sum()
    h, wd, ch = x.shape
    out = np.zeros((h - size + 1, wd - size + 1))
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            vals = []
            for c in range(ch):
                a = x[i:i + size, j:j + size, c]
                b = y[i:i + size, j:j + size, c]
                mu_a, mu_b = (w * a).sum(), (w * b).sum()
                var_a = (w * (a - mu_a) ** 2).sum()
                var_b = (w * (b - mu_b) ** 2).sum()
                cov = (w * (a - mu_a) * (b - mu_b)).sum()
                vals.append(((2 * mu_a * mu_b + SSIM_C1) * (2 * cov + SSIM_C2))
                            / ((mu_a**2 + mu_b**2 + SSIM_C1) * (var_a + var_b + SSIM_C2)))
            out[i, j] = np.mean(vals)
    return out


def test_psnr_of_known_mse() -> None:
    x = torch.zeros(8, 8, 3)
    y = torch.full((8, 8, 3), 0.1)  # MSE 0.01 -> 20 dB
    assert float(psnr(x, y)) == pytest.approx(20.0, abs=1e-6)
    assert math.isinf(float(psnr(x, x)))
    batch = psnr(torch.stack([x, x]), torch.stack([y, torch.full_like(y, 0.01)]))
    assert batch.shape == (2,)
    assert batch.tolist() == pytest.approx([20.0, 40.0], abs=1e-5)


def test_ssim_identity_and_bounds() -> None:
    x, y = _images()
    assert float(ssim(x, x)) == pytest.approx(1.0, abs=1e-9)
    assert float(ssim(x, x, padding="same")) == pytest.approx(1.0, abs=1e-9)
    value = float(ssim(x, y))
    assert 0.0 < value < 1.0
    assert float(dssim_loss(x, x)) == pytest.approx(0.0, abs=1e-9)
    assert float(dssim_loss(x, y)) > 0.0


def test_ssim_map_matches_reference() -> None:
    x, y = _images(seed=3, shape=(17, 20, 3))
    fast = ssim_map(x, y)[0].numpy()
    ref = _ssim_reference(x.numpy(), y.numpy())
    assert fast.shape == ref.shape == (7, 10)
    np.testing.assert_allclose(fast, ref, atol=1e-10)


def test_gaussian_window_normalised() -> None:
    w = gaussian_window()
    assert w.shape == (11,)
    assert float(w.sum()) == pytest.approx(1.0, abs=1e-6)
    assert int(w.argmax()) == 5


def test_masked_psnr_uses_only_masked_pixels() -> None:
    x = torch.zeros(10, 10, 3)
    y = torch.zeros(10, 10, 3)
    y[:5] = 0.1  # error only in the top half
    y[5:] = 0.5
    mask = torch.zeros(10, 10, dtype=torch.bool)
    mask[:5] = True
    assert float(masked_psnr(x, y, mask)) == pytest.approx(20.0, abs=1e-6)
    assert math.isnan(float(masked_psnr(x, y, torch.zeros_like(mask))))
    full = torch.ones_like(mask)
    assert float(masked_psnr(x, y, full)) == pytest.approx(float(psnr(x, y)), abs=1e-9)


def test_masked_ssim_is_mean_of_same_map() -> None:
    x, y = _images(seed=5)
    mask = torch.zeros(x.shape[:2], dtype=torch.bool)
    mask[3:12, 4:20] = True
    smap = ssim_map(x, y, padding="same")[0]
    assert float(masked_ssim(x, y, mask)) == pytest.approx(float(smap[mask].mean()), abs=1e-12)
    assert float(masked_ssim(x, x, mask)) == pytest.approx(1.0, abs=1e-9)
    assert math.isnan(float(masked_ssim(x, y, torch.zeros_like(mask))))


def test_dssim_loss_has_gradient() -> None:
    x, y = _images(seed=1)
    x = x.clone().requires_grad_(True)
    dssim_loss(x, y).backward()
    assert x.grad is not None and bool(torch.isfinite(x.grad).all()) and float(x.grad.abs().sum()) > 0


def test_shape_errors() -> None:
    with pytest.raises(ValueError, match="shapes differ"):
        psnr(torch.zeros(4, 4, 3), torch.zeros(4, 5, 3))
    with pytest.raises(ValueError, match="smaller than the SSIM window"):
        ssim(torch.zeros(5, 5, 3), torch.zeros(5, 5, 3))
    with pytest.raises(ValueError, match="mask shape"):
        masked_psnr(torch.zeros(4, 4, 3), torch.zeros(4, 4, 3), torch.zeros(3, 4, dtype=torch.bool))
