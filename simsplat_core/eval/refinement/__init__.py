"""Evaluation of multi-agent refinement: the ``motion`` table.

* ``real``: rollouts of a predictor on real logs (Waymo Open Motion scenarios, Argoverse 2 logs) against the
  logged future: failure rates (scenario-level and per agent), progress, ADE.
* ``table``: the ``motion`` table's columns, rows -> pyarrow table, Markdown.

The synthetic (edit-based) rows are added beside the real ones (``table.motion_rows``).
"""
