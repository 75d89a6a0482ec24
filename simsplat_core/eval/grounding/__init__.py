"""Grounding evaluation (SIMSplat Tables 2 and 3): the benchmark, the methods it compares, its metrics.

* ``benchmark``: queries generated from a synthetic log's ground truth (``build_benchmark``), each with
  its target objects and instance masks; ``paraphrases`` words them in several styles.
* ``baselines``: LangSplat-like (appearance only) and 4D-LangSplat-like (per-frame captions) grounders
  and the adapter of the ``QueryEngine``; ``methods`` builds the compared methods and the ablation.
* ``metrics``: accuracy and vIoU per category, ``evaluate_grounding`` (runs grounders on a benchmark).
* ``gt_scene``: ``LanguageScene`` s built straight from a log's ground truth (the perfect-mask bound).
* ``calibration``: the engine's no-match and group thresholds chosen on labelled queries.
"""
