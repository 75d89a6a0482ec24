"""Evaluation: everything that measures, on top of the algorithms it measures (which never import it).

* ``image_metrics``: PSNR, SSIM and their masked variants.
* ``grounding/``: the grounding benchmark (queries, paraphrases, ground-truth scenes), the compared
  methods (baselines, ablations), threshold calibration, accuracy / vIoU metrics.
* ``motion``: labeller agreement with the synthetic world and motion grounding accuracy.
* ``captions``: captioner accuracy against ground-truth attributes.
* ``tables``: the evaluation tables (pyarrow and Markdown).
"""

from simsplat_core.eval.image_metrics import (
    dssim_loss,
    masked_psnr,
    masked_ssim,
    psnr,
    ssim,
    ssim_map,
)

__all__ = ["dssim_loss", "masked_psnr", "masked_ssim", "psnr", "ssim", "ssim_map"]
