"""Language alignment and grounding (SIMSplat Sec. 3.2): the method only; its evaluation is ``simsplat_core.eval``.

* ``text``: ``TextEncoder`` protocol, the offline E5 encoder, a registry (``make_text_encoder``).
* (the behaviour vocabulary, trajectories and map context it builds on live in ``simsplat_core.scenario``)
* ``motion_labels``: rule-based auto-labels from trajectories, ego poses and the map.
* ``codebooks``, ``motion_encoder``, ``motion_dataset``, ``motion_training``: the trajectory encoder whose
  outputs are convex combinations of text prototypes (``MotionAligner``).
* ``appearance/``: captions and text-space appearance features per object, their autoencoder.
* ``feature_field``, ``node_masks``, ``scene_builder``, ``scene_language``: per-Gaussian features fitted
  by rendering, rendered node-id maps, and the ``LanguageScene`` built from a reconstructed scene graph.
* ``query_parse``, ``query_lexicon``, ``query_config``, ``query_scoring``, ``query_messages``,
  ``query_result``, ``query``: free-form grounding (``QueryEngine``).
"""
