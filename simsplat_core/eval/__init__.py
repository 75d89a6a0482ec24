"""Evaluation: everything that measures, on top of the algorithms it measures (which never import it).

* ``grounding/``: the grounding benchmark (queries, paraphrases, ground-truth scenes), the compared
  methods (baselines, ablations), threshold calibration, accuracy / vIoU metrics, its tables (``tables``).
* ``editing/``: the editing benchmark (prompts from ground truth, independent checks, edit fidelity, its tables).
* ``refinement/``: the multi-agent refinement evaluation (synthetic and real rollouts, the ``motion`` tables).
* ``search/``: the search benchmark (queries with ground truth from the synthetic world, RefAV metrics).
* ``mining``: mining measures (completion, attempts, plausibility, per category and stage) and their tables.
* ``motion``: labeller agreement with the synthetic world and motion grounding accuracy.
* ``captions``: captioner accuracy against ground-truth attributes.
* ``table_spec``: ``TableSpec``, the declaration of an evaluation table (schema, column meanings and units,
  keys, Markdown and console rendering); each table is declared beside the code that computes it.
* ``table_registry``: every declared table by name (``EVAL_TABLES``, ``table_spec(name)``).
* ``store_tables``: the reconstruction-quality and throughput tables from the figures the stages recorded.
* ``plan``: which evaluations a store's contents allow (``plan_evaluation``), each skipped one with a reason.

Image metrics of reconstructions (PSNR, SSIM, masked variants) are the trainer's validation and live in
``simsplat_core.scene.image_metrics``.
"""
