"""Benchmark: free-form grounding on reconstructed synthetic scenes (SIMSplat Tables 2 and 3), and motion
grounding on the real Argoverse 2 sample.

    .venv/bin/python bench/bench_grounding.py [--bench-seeds 1000 1001 1002 1003 1004] [--calib-seeds]
        [--train-seeds 10] [--iterations 900] [--cache artifacts/bench_grounding] [--out bench/results]

Pipeline (seeds of the three roles are disjoint):

1. **Motion aligner**: ``MotionAligner.fit`` on ``--train-seeds`` annotation-only synthetic logs (seeds
   ``0..N-1``).
2. **Scenes**: every calibration and benchmark seed is generated (``WorldConfig()``: 40 frames, three
   240x160 cameras), reconstructed with the pipeline's default ``ReconstructionConfig`` (``--iterations``
   shortens the schedule) and aligned (``build_language_scene``): node-id maps rendered from the
   Gaussians give every mask, the captioner sees the log's pixels under the *projected* node masks,
   ``f_app`` is decoded from the fitted per-Gaussian features. Reconstructions are cached under
   ``--cache`` (graph records keyed by seed and a hash of the reconstruction config), built scenes too
   (keyed also by a hash of the scene builder's sources); ``--reuse-scenes`` takes cached scenes of any
   builder version, for a quick re-evaluation.
3. **Benchmark**: ``build_benchmark`` on the benchmark logs (``BenchmarkConfig(seed=0)``); calibration
   queries from the calibration logs (``seed=1``).
4. **Methods**: LangSplat-like and 4D-LangSplat-like baselines (``eval.grounding.baselines``), the
   ``QueryEngine`` with all features and the ablations App / App+Mot / App+Loc, all with the engine's
   default thresholds (what the pipeline uses); with ``--calib-seeds`` each variant gets its own
   thresholds from ``calibrate_thresholds`` on queries of those scenes instead (two scenes proved too few:
   a variant could end up refusing most queries). Diagnostics: ``oracle-nodes``
   (answers with the true targets: the vIoU ceiling the reconstruction's masks allow) and ``ours@gt-scene``
   (the engine on scenes built from ground truth: instance masks, captions of ground-truth crops, the same
   aligner -- what grounding achieves with perfect masks).
5. **Outputs**: ``<out>/grounding.json`` (summaries, breakdowns by query kind / family / style, latency,
   failure list and failure classes of the engine, reconstruction and alignment metrics, AV2 motion
   grounding) and ``<out>/grounding.md`` (Table 2 and Table 3 as Markdown).

AV2: ``eval.motion.grounding_accuracy`` of the aligner on the real sample (zero-shot, trained on synthetic
logs only) and on a held-out half of its objects after training with the other half
(``split_objects``); skipped when ``--av2`` does not exist.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import logging
import pickle
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the project's packages (storage, tasks) when run as a script

from simsplat_core.eval.grounding.baselines import (  # noqa: E402
    AppearanceOnlyGrounder,
    EngineGrounder,
    FrameCaptionGrounder,
)
from simsplat_core.eval.grounding.benchmark import (  # noqa: E402
    BenchmarkConfig,
    GroundingBenchmark,
    ObjectFacts,
    build_benchmark,
    generate_queries,
    object_facts,
)
from simsplat_core.eval.grounding.gt_scene import language_scene_from_log  # noqa: E402
from simsplat_core.eval.grounding.methods import ABLATION_ROW_METHODS, engine_variants  # noqa: E402
from simsplat_core.eval.grounding.metrics import GroundingResults, QueryOutcome, evaluate_grounding  # noqa: E402
from simsplat_core.eval.grounding.tables import (  # noqa: E402
    ABLATION_SPEC,
    GROUNDING_SPEC,
    ablation_table,
    grounding_table,
)
from simsplat_core.eval.motion import grounding_accuracy, split_objects  # noqa: E402
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig  # noqa: E402
from simsplat_core.language.scene_language import LanguageScene  # noqa: E402
from simsplat_core.language.text import default_text_encoder  # noqa: E402
from simsplat_core.scene.config import ReconstructionConfig  # noqa: E402
from simsplat_core.types import SceneLog  # noqa: E402
from simsplat_core.world import WorldConfig, generate_log  # noqa: E402

logger = logging.getLogger("bench.grounding")
DEFAULT_AV2 = ROOT.parent / "shared" / "data" / "av2" / "sensor-log-7fab2350"
#: Table 3 rows (display name -> engine variant key of ``grounding_methods``).
ABLATIONS = ABLATION_ROW_METHODS


class OracleNodes:
    """Answers with the benchmark's true targets: the masks' vIoU ceiling."""

    def __init__(self, bench: GroundingBenchmark) -> None:
        self.targets = {(q.seq_id, q.text): q.target_ids for q in bench.queries}

    def ground(self, scene: LanguageScene, text: str) -> tuple[int, ...]:
        node_of = {n.object_id: n.node_id for n in scene.nodes}
        return tuple(node_of[o] for o in self.targets[(scene.seq_id, text)] if o in node_of)


def _builder_version() -> str:
    """Hash of the sources that shape a built scene (a changed builder invalidates cached scenes)."""
    import hashlib

    h = hashlib.sha1()
    for rel in ("simsplat_core/language/alignment/scene_builder.py",
                "simsplat_core/language/alignment/feature_field.py", "simsplat_core/language/node_masks.py"):
        h.update((ROOT / rel).read_bytes())
    return h.hexdigest()[:10]


def _pickle(path: Path, obj) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as fh:
        pickle.dump(obj, fh)
    tmp.replace(path)


def reconstruction_config(iterations: int) -> ReconstructionConfig:
    """The pipeline's default reconstruction with ``iterations`` steps (no train-frame scoring)."""
    return ReconstructionConfig(iterations=iterations, eval_train_frames=0)


def _config_key(config) -> str:
    """Short content key of a reconstruction config (less its run-only fields), as the store keys scenes."""
    from storage.keys import config_settings, content_key
    from tasks.reconstruct import RUN_ONLY_FIELDS

    return content_key("bench-reconstruct", config_settings(config, RUN_ONLY_FIELDS))[:10]


def reconstruction(log: SceneLog, iterations: int, cache: Path):
    """``(graph, info)`` of ``reconstruct(log, reconstruction_config(iterations))``; the graph's records are
    cached by sequence and config."""
    from simsplat_core.scene.graph import SceneGraph
    from simsplat_core.scene.trainer import reconstruct

    config = reconstruction_config(iterations)
    path = cache / f"recon-{log.seq_id}-it{iterations}-{_config_key(config)}.pkl"
    if path.exists():
        with path.open("rb") as fh:
            records, info = pickle.load(fh)
        return SceneGraph.from_records(records), {**info, "cached": True}
    t0 = time.perf_counter()
    result = reconstruct(log, config)
    info = {
        "reconstruct_s": round(time.perf_counter() - t0, 1),
        "psnr_test": round(float(result.metrics["psnr_test"]), 3),
        "psnr_test_dynamic": round(float(result.metrics["psnr_test_dynamic"]), 3),
        "num_gaussians": int(result.metrics["num_gaussians"]),
    }
    _pickle(path, (result.graph.to_records(log.seq_id), info))
    return result.graph, {**info, "cached": False}


def reconstructed_scene(log: SceneLog, iterations: int, encoder, aligner, cache: Path, tag: str = "",
                        reuse_scenes: bool = False) -> tuple[LanguageScene, dict]:
    """Reconstruct (cached) and align one log.

    Built scenes are cached too, keyed by the builder's sources and ``tag`` (the aligner's training
    seeds); ``reuse_scenes`` accepts a cached scene of any builder version (quick re-evaluation).
    """
    from simsplat_core.language.alignment.scene_builder import AlignmentConfig, build_language_scene

    stem = f"scene-{log.seq_id}-it{iterations}-{_config_key(reconstruction_config(iterations))}"
    path = cache / f"{stem}-{_builder_version()}{tag}.pkl"
    candidates = [path] if path.exists() else (sorted(cache.glob(f"{stem}-*{tag}.pkl")) if reuse_scenes else [])
    if candidates:
        with candidates[-1].open("rb") as fh:
            scene, info = pickle.load(fh)
        if scene.text_encoder == encoder.name:
            return scene, {**info, "scene_cache": candidates[-1].name}
    graph, info = reconstruction(log, iterations, cache)
    t0 = time.perf_counter()
    built = build_language_scene(graph, log, text_encoder=encoder, aligner=aligner, config=AlignmentConfig())
    info = {**info, "align_s": round(time.perf_counter() - t0, 1),
            "alignment": {k: round(float(v), 4) for k, v in built.metrics.items()}, "builder": _builder_version()}
    _pickle(path, (built.scene, info))
    return built.scene, info


def engine_methods(encoder, calib_examples, codebooks=None) -> tuple[dict, dict]:
    """The QueryEngine ablations, each calibrated on ``calib_examples`` (the engine's default thresholds when
    there are none); returns ``(grounders, thresholds)``."""
    from simsplat_core.eval.grounding.calibration import calibrate_thresholds
    from simsplat_core.language.grounding.config import QueryConfig
    from simsplat_core.language.grounding.engine import QueryEngine

    variants = engine_variants(QueryEngine(encoder, QueryConfig(), codebooks))
    grounders, thresholds = {}, {}
    for name, key in ABLATIONS.items():
        engine = variants[key]
        t0 = time.perf_counter()
        config = calibrate_thresholds(engine, calib_examples) if calib_examples else engine.config
        engine = engine.with_config(config)
        grounders[name] = EngineGrounder(engine, name)
        thresholds[name] = {
            "no_match_threshold": round(config.no_match_threshold, 4),
            "group_threshold": round(config.group_threshold, 4),
            "calibration_s": round(time.perf_counter() - t0, 1),
        }
        logger.info("%s: thresholds %s", name, thresholds[name])
    return grounders, thresholds


def calibration_examples(logs: list[SceneLog], scenes: dict[str, LanguageScene]) -> list[tuple]:
    examples = []
    for log in logs:
        scene = scenes[log.seq_id]
        node_of = {n.object_id: n.node_id for n in scene.nodes}
        for q in generate_queries(log, BenchmarkConfig(seed=1)):
            examples.append((scene, q.text, frozenset(node_of[o] for o in q.target_ids if o in node_of)))
    return examples


def failure_class(o: QueryOutcome, facts: dict[str, ObjectFacts], scene: LanguageScene) -> str:
    """A coarse reason for a wrong answer, from the ground truth of the objects involved."""
    q = o.query
    pred, tgt = set(o.predicted), set(q.target_ids)
    if q.kind == "none":
        return "none: answered a no-match query" + (f" (changed {q.perturbed})" if q.perturbed else "")
    node_of = {n.object_id: n for n in scene.nodes}
    if any(node_of.get(t) is None or node_of[t].f_app is None for t in tgt):
        return f"{q.kind}: a target has no appearance feature"
    if not pred:
        return f"{q.kind}: empty answer"
    if q.kind == "group":
        if pred > tgt:
            return "group: extra members"
        if pred < tgt:
            return "group: missing members"
        return "group: wrong members"
    (target,) = tgt
    wrong = sorted(pred - tgt)
    if len(pred) > 1:
        return "single: several objects returned"
    t, p = facts[target], facts[wrong[0]]
    if t.category != p.category:
        return "single: wrong category"
    d = q.description
    app_slots = [s for s in ("subtype", "color", "upper", "lower") if getattr(d, s) is not None]
    app_differs = [s for s in app_slots if getattr(p, s) != getattr(t, s)]
    if app_differs:
        cap = node_of[target].caption
        cap_wrong = cap is None or any(
            (s == "color" and cap.color != t.color) or (s == "subtype" and cap.subtype != t.subtype)
            or (s == "upper" and cap.upper_color != t.upper) or (s == "lower" and cap.lower_color != t.lower)
            for s in app_differs
        )
        return "single: appearance (target's caption wrong)" if cap_wrong else "single: appearance (caption right)"
    if d.motion is not None and p.motion != t.motion:
        return "single: motion"
    if (d.sector is not None and p.sector != t.sector) or (d.context is not None and p.context != t.context):
        return "single: location"
    return "single: other"


def engine_trace(grounder: EngineGrounder, scene: LanguageScene, o: QueryOutcome,
                 facts: dict[str, ObjectFacts]) -> dict:
    """What the engine made of a failed query: parsed parts, message, and the involved objects' facts."""
    g = grounder.engine.ground(scene, o.query.text)
    p = g.parsed
    node_of = {n.object_id: n for n in scene.nodes}

    def describe(oid: str) -> dict:
        f, n = facts[oid], node_of.get(oid)
        cap = n.caption.text if n is not None and n.caption is not None else None
        mot = n.motion.motion if n is not None and n.motion is not None else None
        return {"gt": f"{f.color or f.upper or ''}/{f.subtype or f.lower or ''} {f.motion} {f.sector} {f.context}",
                "caption": cap, "aligner_motion": mot}

    return {
        "parsed": {"noun": p.noun, "subtype": p.subtype, "colors": list(p.colors), "upper": p.upper_color,
                   "lower": p.lower_color, "motion": p.motion, "direction": p.crossing_direction,
                   "sector": p.sector, "context": p.context, "group": p.group},
        "message": g.message,
        "objects": {oid: describe(oid) for oid in sorted(set(o.query.target_ids) | set(o.predicted))},
        "description": {k: v for k, v in dataclasses.asdict(o.query.description).items() if v is not None},
    }


def size_breakdown(results: GroundingResults, method: str, facts: dict[str, dict[str, ObjectFacts]],
                   scenes: dict[str, LanguageScene]) -> dict:
    """Single-target accuracy / vIoU by the target's largest per-frame size and by whether its node has ``f_app``."""
    groups: dict[str, list[QueryOutcome]] = collections.defaultdict(list)
    for o in results.for_method(method):
        if o.query.kind != "single":
            continue
        f = facts[o.query.seq_id][o.query.target_ids[0]]
        px = f.max_frame_pixels
        size = "<100 px" if px < 100 else ("100-400 px" if px < 400 else ">=400 px")
        node = {n.object_id: n for n in scenes[o.query.seq_id].nodes}.get(f.object_id)
        feat = "with f_app" if node is not None and node.f_app is not None else "without f_app"
        groups[f"size {size}"].append(o)
        groups[feat].append(o)
    return {k: {"queries": len(v), "acc": round(float(np.mean([o.correct for o in v])), 4),
                "viou": round(float(np.mean([o.viou for o in v])), 4)} for k, v in sorted(groups.items())}


def summary_json(results: GroundingResults) -> dict:
    out = {}
    for method, per in results.summary().items():
        out[method] = {c: {"acc": round(s.accuracy, 4), "viou": round(s.viou, 4), "queries": s.queries}
                       for c, s in per.items()}
    return out


def breakdowns(results: GroundingResults, method: str) -> dict:
    return {
        key: {k: {"acc": round(v.accuracy, 4), "viou": round(v.viou, 4), "queries": v.queries}
              for k, v in results.breakdown(method, key).items()}
        for key in ("kind", "family", "style")
    }


def cold_latency(engine_grounder: EngineGrounder, scenes: dict[str, LanguageScene], bench: GroundingBenchmark,
                 count: int = 30) -> dict:
    """Seconds per ``ground`` call with nothing cached: a fresh E5 encoder (one-entry cache) and engine."""
    from simsplat_core.language.grounding.engine import QueryEngine
    from simsplat_core.language.text import E5TextEncoder

    engine = engine_grounder.engine
    fresh = QueryEngine(E5TextEncoder(cache_size=1), engine.config, engine.codebooks, cache_size=1)
    fresh.text_encoder.encode_queries(["warm-up"])
    queries = bench.queries[:: max(1, len(bench.queries) // count)][:count]
    secs = []
    for q in queries:
        t0 = time.perf_counter()
        fresh.ground(scenes[q.seq_id], q.text)
        secs.append(time.perf_counter() - t0)
    return {"queries": len(secs), "median_s": round(float(np.median(secs)), 4),
            "p90_s": round(float(np.percentile(secs, 90)), 4), "max_s": round(float(np.max(secs)), 4)}


def av2_motion(aligner, train_logs, encoder, path: Path) -> dict:
    if not path.is_dir():
        logger.warning("AV2 sample not found at %s; skipping", path)
        return {"skipped": f"{path} not found"}
    from simsplat_core.data.av2 import load_av2_log

    av2 = load_av2_log(path)
    zero = grounding_accuracy(aligner, [av2], encoder)
    half_a, half_b = split_objects(av2, seed=0)
    with_half = MotionAligner.fit([*train_logs, half_a], aligner.config, encoder)
    held = grounding_accuracy(with_half, [half_b], encoder)
    r = lambda s: {k: round(v, 4) if isinstance(v, float) else v for k, v in s.summary().items()}  # noqa: E731
    return {
        "log": path.name,
        "zero_shot_trained_on_synthetic": r(zero),
        "held_out_half_trained_with_other_half": r(held),
        "per_class_held_out_half": {k: [n, round(a, 3), round(o, 3)]
                                    for k, (n, a, o) in sorted(held.per_class.items())},
    }


def _parse_args() -> argparse.Namespace:
    """The command line (module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bench-seeds", type=int, nargs="+", default=[1000, 1001, 1002, 1003, 1004])
    parser.add_argument("--calib-seeds", type=int, nargs="*", default=[],
                        help="calibrate each variant's thresholds on these scenes (default: engine defaults)")
    parser.add_argument("--train-seeds", type=int, default=10)
    parser.add_argument("--iterations", type=int, default=ReconstructionConfig().iterations,
                        help="reconstruction steps (default: the pipeline's schedule)")
    parser.add_argument("--cache", type=Path, default=ROOT / "artifacts" / "bench_grounding")
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results")
    parser.add_argument("--av2", type=Path, default=DEFAULT_AV2)
    parser.add_argument("--no-gt-scenes", action="store_true", help="skip the ours@gt-scene diagnostic")
    parser.add_argument("--reuse-scenes", action="store_true",
                        help="use cached language scenes built by another version of the scene builder")
    return parser.parse_args()


def _failure_analysis(results: GroundingResults, engines: dict, scenes: dict[str, LanguageScene],
                      facts: dict) -> tuple[dict[str, dict], list[dict]]:
    """Failure classes of each ablation's wrong answers, and every wrong answer of the full method with the
    engine's trace."""
    failures = []
    classes: dict[str, collections.Counter] = {}
    for name in ABLATIONS:
        counter = collections.Counter()
        for o in results.for_method(name):
            if o.correct:
                continue
            cls = failure_class(o, facts[o.query.seq_id], scenes[o.query.seq_id])
            counter[cls] += 1
            if name == "All":
                failures.append({"query": o.query.text, "seq": o.query.seq_id, "kind": o.query.kind,
                                 "family": o.query.family, "style": o.query.style, "targets": list(o.query.target_ids),
                                 "predicted": list(o.predicted), "class": cls, "viou": round(o.viou, 3),
                                 **engine_trace(engines["All"], scenes[o.query.seq_id], o, facts[o.query.seq_id])})
        classes[name] = dict(counter.most_common())
    return classes, failures


def _reconstruct_all(logs: list[SceneLog], args: argparse.Namespace, encoder, aligner
                     ) -> tuple[dict[str, LanguageScene], dict[str, dict]]:
    """``seq_id -> language scene`` and ``seq_id -> build info`` of every log (:func:`reconstructed_scene`)."""
    scenes: dict[str, LanguageScene] = {}
    scene_info: dict[str, dict] = {}
    for log in logs:
        scene, info = reconstructed_scene(log, args.iterations, encoder, aligner, args.cache, f"-tr{args.train_seeds}",
                                          args.reuse_scenes)
        scenes[log.seq_id] = scene
        scene_info[log.seq_id] = info
        logger.info("%s: %s", log.seq_id, {k: v for k, v in info.items() if k != "alignment"})
    return scenes, scene_info


def _write_report(args: argparse.Namespace, result: dict, bench, bench_logs: list[SceneLog], table2, table3,
                  diagnostics) -> None:
    """``grounding.json`` (``result``) and ``grounding.md`` (Tables 2, 3 and the diagnostics) under ``args.out``."""
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "grounding.json").write_text(json.dumps(result, indent=2) + "\n")
    thresholds = (f"thresholds calibrated on seeds {args.calib_seeds}" if args.calib_seeds
                  else "default engine thresholds")
    md = [
        "# Grounding benchmark",
        "",
        f"{len(bench.queries)} queries on {len(bench_logs)} reconstructed synthetic scenes "
        f"(seeds {args.bench_seeds}, {args.iterations} reconstruction iterations, "
        f"{thresholds}); counts {bench.counts()}.",
        "",
        "## Table 2: methods",
        "",
        GROUNDING_SPEC.render_markdown(table2),
        "## Table 3: feature ablation",
        "",
        ABLATION_SPEC.render_markdown(table3),
        "## Diagnostics",
        "",
        GROUNDING_SPEC.render_markdown(diagnostics),
    ]
    (args.out / "grounding.md").write_text("\n".join(md))
    logger.info("Table 2\n%s", GROUNDING_SPEC.render_markdown(table2))
    logger.info("Table 3\n%s", ABLATION_SPEC.render_markdown(table3))
    logger.info("Diagnostics\n%s", GROUNDING_SPEC.render_markdown(diagnostics))
    logger.info("wrote %s and %s", args.out / "grounding.json", args.out / "grounding.md")


def main() -> None:
    args = _parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    for noisy in ("simsplat_core.scene.trainer", "simsplat_core.language.alignment.feature_field"):
        logging.getLogger(noisy).setLevel(logging.WARNING)
    bench_and_calib = set(args.bench_seeds) | set(args.calib_seeds)
    if set(args.bench_seeds) & set(args.calib_seeds) or bench_and_calib & set(range(args.train_seeds)):
        raise SystemExit("benchmark, calibration and training seeds must be disjoint")
    t_start = time.perf_counter()
    result: dict = {"machine": {"cpu": platform.processor() or platform.machine(), "python": platform.python_version()}}
    encoder = default_text_encoder()

    t0 = time.perf_counter()
    train_logs = [generate_log(s, WorldConfig(render_images=False)) for s in range(args.train_seeds)]
    aligner = MotionAligner.fit(train_logs, MotionAlignerConfig(), encoder)
    result["aligner"] = {"train_seeds": f"0..{args.train_seeds - 1}", "fit_s": round(time.perf_counter() - t0, 1)}

    world = WorldConfig()
    logs = {s: generate_log(s, world) for s in [*args.calib_seeds, *args.bench_seeds]}
    scenes, scene_info = _reconstruct_all(list(logs.values()), args, encoder, aligner)
    result["scenes"] = {"world": {"frames": world.num_frames, "size": [world.width, world.height],
                                  "cameras": [c.name for c in world.cameras]},
                        "iterations": args.iterations, "per_scene": scene_info}

    bench_logs = [logs[s] for s in args.bench_seeds]
    bench = build_benchmark(bench_logs, BenchmarkConfig(seed=0))
    calib_logs = [logs[s] for s in args.calib_seeds]
    examples = calibration_examples(calib_logs, scenes)
    result["benchmark"] = {"bench_seeds": args.bench_seeds, "calib_seeds": args.calib_seeds,
                           "counts": bench.counts(), "calibration_queries": len(examples),
                           "config": dataclasses.asdict(bench.config),
                           "examples": [q.text for q in bench.queries[:: max(1, len(bench.queries) // 25)]]}

    engines, thresholds = engine_methods(encoder, examples)
    result["thresholds"] = thresholds
    log_by_seq = {log.seq_id: log for log in logs.values()}
    methods = {
        "LangSplat-like": AppearanceOnlyGrounder(encoder),
        "4D-LangSplat-like": FrameCaptionGrounder(encoder, log_by_seq),
        **engines,
        "oracle-nodes": OracleNodes(bench),
    }
    bench_scenes = [scenes[log.seq_id] for log in bench_logs]
    t0 = time.perf_counter()
    results = evaluate_grounding(bench_scenes, bench, methods)
    result["evaluation_s"] = round(time.perf_counter() - t0, 1)
    summary = results.summary()

    if not args.no_gt_scenes:
        gt_scenes = [language_scene_from_log(log, encoder, "captioner", aligner=aligner) for log in bench_logs]
        gt_results = evaluate_grounding(gt_scenes, bench, {"ours@gt-scene": engines["All"]})
        summary.update(gt_results.summary())
        result["ours_at_gt_scene"] = {"summary": summary_json(gt_results),
                                      "breakdown": breakdowns(gt_results, "ours@gt-scene")}

    table2 = grounding_table(summary, {"LangSplat-like": "LangSplat-like", "4D-LangSplat-like": "4D-LangSplat-like",
                                       "Ours": "All"})
    table3 = ablation_table(summary, {name: name for name in ABLATIONS})
    diag_rows = {"Ours": "All", "oracle nodes (vIoU ceiling)": "oracle-nodes"}
    if "ours@gt-scene" in summary:
        diag_rows["Ours on GT-built scenes"] = "ours@gt-scene"
    diagnostics = grounding_table(summary, diag_rows)
    result["summary"] = summary_json(results)
    if "ours@gt-scene" in summary:
        result["summary"]["ours@gt-scene"] = result["ours_at_gt_scene"]["summary"]["ours@gt-scene"]
    result["breakdown"] = {m: breakdowns(results, m) for m in methods if m != "oracle-nodes"}
    result["latency_s"] = {m: {k: round(v, 4) for k, v in results.latency(m).items()} for m in methods}
    result["latency_s"]["note"] = ("per-method latency within the run: text embeddings are cached across methods "
                                   "(LangSplat-like pays E5 first); ours_cold is a fresh encoder and engine")
    result["latency_s"]["ours_cold"] = cold_latency(engines["All"], scenes, bench)

    facts = {log.seq_id: object_facts(log) for log in bench_logs}
    classes, failures = _failure_analysis(results, engines, scenes, facts)
    result["failure_classes"] = classes
    result["single_by_target"] = {m: size_breakdown(results, m, facts, scenes)
                                  for m in ("All", "LangSplat-like", "oracle-nodes")}
    result["failures_ours"] = failures
    result["wall_time_s"] = round(time.perf_counter() - t_start, 1)

    result["av2_motion_grounding"] = av2_motion(aligner, train_logs, encoder, args.av2)

    _write_report(args, result, bench, bench_logs, table2, table3, diagnostics)


if __name__ == "__main__":
    main()
