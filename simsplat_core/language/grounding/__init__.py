"""Free-form grounding (SIMSplat Sec. 3.2): descriptions -> scene-graph nodes and per-frame pixel masks.

* ``engine``: ``QueryEngine`` (appearance narrows the candidates, motion and location choose).
* ``parse``: a description split into its appearance, motion and location parts (``parse_query``).
* ``lexicon``: which words name which motion, location, colour and subtype.
* ``config``: ``QueryConfig``, the engine's switches, weights and thresholds.
* ``scoring``: the per-signal match scores as pure functions.
* ``messages``: the answer in words; ``result``: ``NodeMatch`` and ``Grounding``.
* ``static_location``: ego-relative sector shares of static objects, derived from the log.

It reads a built ``LanguageScene`` and the shared pieces of ``simsplat_core.language``, never the alignment
side.
"""
