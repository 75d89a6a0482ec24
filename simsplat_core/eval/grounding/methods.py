"""The grounding methods compared in the evaluation tables (SIMSplat Tables 2 and 3), built in one place.

    methods = grounding_methods(encoder, logs_by_seq)          # name -> Grounder
    results = evaluate_grounding(scenes, benchmark, methods)
    table2 = grounding_table(results.summary(), COMPARISON_ROWS)
    table3 = ablation_table(results.summary(), ABLATION_ROW_METHODS)

Table 2 compares an appearance-only LangSplat-like baseline, an appearance + per-frame caption
4D-LangSplat-like baseline and this method; Table 3 ablates this method's features (App / App+Mot /
App+Loc / All). Every engine variant shares one text encoder, codebooks and embedding cache.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from simsplat_core.eval.grounding.baselines import AppearanceOnlyGrounder, EngineGrounder, FrameCaptionGrounder
from simsplat_core.eval.grounding.metrics import Grounder
from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import TextEncoder
from simsplat_core.types import SceneLog

#: Table 2 rows: display name -> method key.
COMPARISON_ROWS: dict[str, str] = {"LangSplat-like (appearance)": "langsplat",
                                   "4D-LangSplat-like (appearance + frame captions)": "4d-langsplat",
                                   "SIMSplat (ours)": "ours"}
#: Table 3 rows: display name -> method key, and the (use_motion, use_location) of each.
ABLATION_ROW_METHODS: dict[str, str] = {"App": "ours-app", "App+Mot": "ours-app-mot", "App+Loc": "ours-app-loc",
                                        "All": "ours"}
ABLATION_FEATURES: dict[str, tuple[bool, bool]] = {"ours-app": (False, False), "ours-app-mot": (True, False),
                                                   "ours-app-loc": (False, True), "ours": (True, True)}


def engine_variants(engine: QueryEngine, configs: Mapping[str, QueryConfig] | None = None) -> dict[str, QueryEngine]:
    """The four feature ablations of ``engine`` (``ABLATION_FEATURES``), sharing its encoder and cache.

    ``configs`` may give each variant its own (e.g. calibrated) config; otherwise the engine's config
    with the variant's feature switches.
    """
    out = {}
    for key, (motion, location) in ABLATION_FEATURES.items():
        base = (configs or {}).get(key, engine.config)
        out[key] = engine.with_config(dataclasses.replace(base, use_motion=motion, use_location=location))
    return out


def grounding_methods(encoder: TextEncoder, logs: Mapping[str, SceneLog], engine: QueryEngine | None = None,
                      configs: Mapping[str, QueryConfig] | None = None) -> dict[str, Grounder]:
    """Every method of Tables 2 and 3 by key: the two baselines and the engine's ablations.

    Args:
        logs: ``seq_id -> log`` (the per-frame caption baseline reads the tracks).
        engine: the engine to ablate (default ``QueryEngine(encoder)``).
        configs: per-variant engine configs (see :func:`engine_variants`).
    """
    engine = engine or QueryEngine(encoder)
    methods: dict[str, Grounder] = {"langsplat": AppearanceOnlyGrounder(encoder),
                                  "4d-langsplat": FrameCaptionGrounder(encoder, dict(logs))}
    methods.update({key: EngineGrounder(variant, key) for key, variant in engine_variants(engine, configs).items()})
    return methods
