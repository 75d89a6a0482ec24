"""Language alignment and grounding (SIMSplat Sec. 3.2): the method only; its evaluation is ``simsplat_core.eval``.

Two subpackages over shared pieces:

* ``alignment/``: builds language features for a reconstructed scene (trajectory aligner, feature field,
  ``build_language_scene``);
* ``grounding/``: answers free-form descriptions on a built scene (``QueryEngine``, query parsing and scoring).

Shared by both (they import these, these import neither):

* ``text``: ``TextEncoder`` protocol, the offline E5 encoder, a registry (``make_text_encoder``).
* ``codebooks``: the motion and location codebooks whose prototypes are text embeddings (alignment trains
  against them, grounding compares queries with them).
* ``motion_labels``: rule-based auto-labels from trajectories, ego poses and the map.
* ``node_masks``: node-id maps rendered from a scene graph, the crops they cut, their agreement with instance masks.
* ``scene_language``: the ``LanguageScene`` record (per node ``NodeLanguage`` with ``ObjectMotionFeatures``).
* ``appearance/``: captions and text-space appearance features per object, their autoencoder (its
  ``vlm_captioner`` reads a model's reply with ``grounding.parse``, which imports nothing else of this package).
* (the behaviour vocabulary, trajectories and map context it builds on live in ``simsplat_core.scenario``)
"""
