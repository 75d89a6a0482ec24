"""Language alignment (SIMSplat Sec. 3.2): language features fitted to a reconstructed scene.

* ``motion_encoder``, ``motion_dataset``, ``motion_training``: the trajectory encoder whose outputs are convex
  combinations of the codebooks' text prototypes (``MotionAligner``), its training samples and loss.
* ``feature_field``: per-Gaussian appearance latents fitted by rendering against the node-id maps.
* ``scene_builder``: ``build_language_scene``, the pipeline from a scene graph and its log to a ``LanguageScene``
  (node-id maps, crops, captions, the scene's autoencoder, the feature field, motion features).

It reads the shared pieces of ``simsplat_core.language`` (text space, codebooks, auto-labels, node-id maps,
appearance, the ``LanguageScene`` record) and never the grounding side.
"""
