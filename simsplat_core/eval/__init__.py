"""Evaluation: everything that measures, on top of the algorithms it measures (which never import it).

* ``grounding/``: the grounding benchmark (queries, paraphrases, ground-truth scenes), the compared
  methods (baselines, ablations), threshold calibration, accuracy / vIoU metrics.
* ``motion``: labeller agreement with the synthetic world and motion grounding accuracy.
* ``captions``: captioner accuracy against ground-truth attributes.
* ``tables``: the evaluation tables (pyarrow and Markdown).

Image metrics of reconstructions (PSNR, SSIM, masked variants) are the trainer's validation and live in
``simsplat_core.scene.image_metrics``.
"""
