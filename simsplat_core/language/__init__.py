"""Language alignment (SIMSplat Sec. 3.2): the text space and motion/location features.

* ``text``: ``TextEncoder`` protocol, the offline E5 encoder, a registry (``make_text_encoder``).
* ``vocabulary``: motion / location classes with prototype and query phrasings.
* ``motion_labels``: rule-based auto-labels from trajectories, ego poses and the map.
* ``codebooks``, ``motion_encoder``, ``motion_training``: the trajectory encoder whose outputs are
  convex combinations of text prototypes (``MotionAligner``).
* ``motion_eval``: labeller agreement and grounding accuracy.
"""
