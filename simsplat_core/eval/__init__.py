"""Evaluation: image metrics (PSNR, SSIM, masked variants); grounding and motion metrics come later."""

from simsplat_core.eval.image_metrics import (
    dssim_loss,
    masked_psnr,
    masked_ssim,
    psnr,
    ssim,
    ssim_map,
)

__all__ = ["dssim_loss", "masked_psnr", "masked_ssim", "psnr", "ssim", "ssim_map"]
