"""Benchmark: building a LanguageScene from a reconstructed synthetic sequence (appearance alignment).

    .venv/bin/python bench/bench_alignment.py [--seed 0] [--iterations 100] [--aligner-epochs 10]
                                              [--compare-vocabulary] [--cache /tmp/alignment_scene.pkl]

Generates the default synthetic sequence (``WorldConfig()``: 40 frames, 3 cameras at 240x160),
reconstructs it with a short schedule (``ReconstructionConfig(iterations=...)``), trains a small
motion aligner on the log, then runs ``build_language_scene`` with the default ``AlignmentConfig``.
Writes ``bench/results/alignment.json``:

* ``times``: wall seconds per stage of the build (node-id maps of all frames, crops, captions, the
  autoencoder, the feature field, motion) and the total; generation / reconstruction / aligner
  training separately;
* ``masks``: projected node masks against the ground-truth instance masks (IoU per object pooled over
  all 120 images, mean over objects with >= ``min_area`` pixels, pooled IoU, pixel accuracy), for all
  frames and for the held-out frames only;
* ``feature_field``: the fit before/after (latent MSE over all / object pixels, mean cosine between the
  decoded rendered feature and the owning node's text feature over all / object pixels, nearest-target
  accuracy on object pixels), and how well each node's ``f_app`` matches its caption embedding;
* ``relevance``: for each captioned object, the relevance map of its ground-truth appearance caption
  (as a query) on a frame where it is large: mean relevance on its own pixels, on other objects'
  pixels and on the background;
* ``background_latent``: mean cosine of the object-caption queries with the decoded background latent
  (the passage, as used) and with the decoded zero latent (the alternative);
* ``objects``: per object its caption, ground-truth caption, IoU, whether it got ``f_app`` / motion.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import os
import pickle
import platform
import time
from pathlib import Path

import numpy as np

from simsplat_core.language.alignment.feature_field import similarity_map
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import AlignmentConfig, build_language_scene
from simsplat_core.language.node_masks import NodeIdMaps, mask_agreement
from simsplat_core.language.text import default_text_encoder
from simsplat_core.scene import ReconstructionConfig, reconstruct
from simsplat_core.world import WorldConfig, generate_log

logger = logging.getLogger("bench.alignment")
OUT = Path(__file__).resolve().parent / "results" / "alignment.json"


def r4(x: float) -> float:
    return round(float(x), 4)


def load_scene(seed: int, iterations: int, cache: str | None):
    """``(log, graph, timings)``; reused from ``cache`` when it holds the same seed and schedule."""
    if cache and os.path.exists(cache):
        with open(cache, "rb") as fh:
            stored = pickle.load(fh)
        if stored["seed"] == seed and stored["iterations"] == iterations:
            logger.info("reusing the reconstruction cached in %s", cache)
            return stored["log"], stored["graph"], {**stored["times"], "reconstruction_cached": True}
    t0 = time.perf_counter()
    log = generate_log(seed, WorldConfig())
    t1 = time.perf_counter()
    result = reconstruct(log, ReconstructionConfig(iterations=iterations))
    times = {"generate_s": r4(t1 - t0), "reconstruct_s": r4(time.perf_counter() - t1),
             "reconstruct_psnr_test": r4(result.metrics["psnr_test"])}
    if cache:
        with open(cache, "wb") as fh:
            pickle.dump({"seed": seed, "iterations": iterations, "log": log, "graph": result.graph, "times": times}, fh)
    return log, result.graph, times


def relevance(built, graph, log, encoder, max_objects: int = 8) -> dict:
    """Relevance of each captioned object's ground-truth caption on its own pixels vs. elsewhere."""
    scene = built.scene
    gt = {o.object_id: o.attributes.get("caption_appearance", "") for o in log.objects}
    rows = []
    for node in [n for n in scene.nodes if n.f_app is not None][:max_objects]:
        frame = scene.busiest_frame(scene.masks([node.node_id]))
        frame_row = int(np.flatnonzero(scene.frame_indices == frame)[0])
        images = sorted(log.images_at(frame), key=lambda img: scene.cameras.index(img.camera))
        q = encoder.encode_queries([gt[node.object_id]])[0]
        sim = similarity_map(graph, frame, np.stack([i.cam_to_world for i in images]), np.stack([i.K for i in images]),
                             images[0].width, images[0].height, built.autoencoder, q)
        ids = scene.node_id_maps[frame_row]
        own = ids == node.node_id
        other = (ids > 0) & ~own
        background = ids <= 0
        rows.append({"object": node.object_id, "query": gt[node.object_id], "frame": frame,
                     "own": r4(sim[own].mean()), "other_objects": r4(sim[other].mean()) if other.any() else None,
                     "background": r4(sim[background].mean())})
    margins = [r["own"] - r["other_objects"] for r in rows if r["other_objects"] is not None]
    return {"per_object": rows, "mean_own_minus_other": r4(np.mean(margins)) if margins else None,
            "mean_own_minus_background": r4(np.mean([r["own"] - r["background"] for r in rows])) if rows else None}


def background_choice(built, log, encoder) -> dict:
    ae = built.autoencoder
    queries = encoder.encode_queries([o.attributes.get("caption_appearance", "") for o in log.objects])
    z_bg = ae.encode(encoder.encode_passages([AlignmentConfig().background_passage]))
    passage = ae.decode(z_bg)[0]
    zero = ae.decode(np.zeros((1, ae.latent_dim), np.float32))[0]
    row_of = {o.object_id: i for i, o in enumerate(log.objects)}
    own = np.array([float(n.f_app @ queries[row_of[n.object_id]])
                    for n in built.scene.nodes if n.f_app is not None and n.object_id in row_of])
    return {"query_cos_with_decoded_passage_latent": r4((queries @ passage).mean()),
            "query_cos_with_decoded_zero_latent": r4((queries @ zero).mean()),
            "query_cos_with_own_f_app": r4(own.mean()) if own.size else None}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=100, help="reconstruction iterations")
    parser.add_argument("--aligner-epochs", type=int, default=10)
    parser.add_argument("--compare-vocabulary", action="store_true",
                        help="also build with use_vocabulary=True (autoencoder on the caption vocabulary too)")
    parser.add_argument("--cache", default=None, help="pickle of the reconstruction to reuse between runs")
    parser.add_argument("--out", default=str(OUT))
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    load_before = os.getloadavg()

    log, graph, scene_times = load_scene(args.seed, args.iterations, args.cache)
    encoder = default_text_encoder()
    t0 = time.perf_counter()
    aligner = MotionAligner.fit([log], MotionAlignerConfig(epochs=args.aligner_epochs), encoder)
    aligner_s = time.perf_counter() - t0

    config = AlignmentConfig()
    built = build_language_scene(graph, log, text_encoder=encoder, aligner=aligner, config=config)
    m = built.metrics
    scene = built.scene
    sizes = {img.camera: (img.width, img.height) for img in log.images}
    maps = NodeIdMaps(scene.frame_indices, scene.cameras, scene.node_id_maps, tuple(sizes[c] for c in scene.cameras))
    test_frames = sorted({img.frame_idx for img in log.images if img.split == "test"})
    all_masks = mask_agreement(log, maps, graph, min_gt_pixels=config.min_area)
    test_masks = mask_agreement(log, maps, graph, frames=test_frames, min_gt_pixels=config.min_area)

    objects = []
    gt = {o.object_id: o for o in log.objects}
    for node in scene.nodes:
        objects.append({
            "object": node.object_id, "category": node.category,
            "gt_caption": gt[node.object_id].attributes.get("caption_appearance"),
            "caption": None if node.caption is None else node.caption.text,
            "iou": r4(all_masks.object_iou.get(node.object_id, float("nan"))),
            "gt_pixels": all_masks.object_gt_pixels.get(node.object_id, 0),
            "f_app": node.f_app is not None, "motion": None if node.motion is None else node.motion.motion,
        })
    captioned = [o for o in objects if o["caption"]]
    result = {
        "machine": {"cpu": platform.machine(), "cores": os.cpu_count(), "python": platform.python_version(),
                    "load_average_before": [round(v, 2) for v in load_before]},
        "sequence": {"seed": args.seed, "frames": log.num_frames, "cameras": 3, "image_size": [240, 160],
                     "objects": len(log.objects), "reconstruction_iterations": args.iterations},
        "config": {k: v for k, v in dataclasses.asdict(config).items()},
        "times": {**{k[5:]: r4(v) for k, v in m.items() if k.startswith("time_")},
                  **scene_times, "aligner_training_s": r4(aligner_s)},
        "masks": {"all_frames": {k: r4(v) for k, v in all_masks.summary().items()},
                  "held_out_frames": {k: r4(v) for k, v in test_masks.summary().items()}},
        "feature_field": {k: r4(v) for k, v in m.items() if k.startswith("fit_") or k == "f_app_vs_caption_cosine"},
        "counts": {"crops": int(m["crops"]), "object_nodes": int(m["object_nodes"]),
                   "nodes_with_f_app": int(m["nodes_with_f_app"]), "nodes_with_motion": int(m["nodes_with_motion"]),
                   "captions_matching_gt": sum(o["caption"] == (o["gt_caption"] or "").replace(" pants", " trousers")
                                               for o in captioned)},
        "relevance": relevance(built, built.graph, log, encoder),
        "background_latent": background_choice(built, log, encoder),
        "objects": objects,
    }
    if args.compare_vocabulary:
        vocab = build_language_scene(graph, log, text_encoder=encoder, aligner=None,
                                     config=dataclasses.replace(config, use_vocabulary=True, measure_masks=False))
        result["with_vocabulary"] = {k: r4(v) for k, v in vocab.metrics.items()
                                     if k.startswith(("time_", "fit_")) or k == "f_app_vs_caption_cosine"}
    result["machine"]["load_average_after"] = [round(v, 2) for v in os.getloadavg()]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    logger.info("wrote %s", args.out)
    print(json.dumps({k: result[k] for k in ("times", "masks", "feature_field", "counts")}, indent=1))


if __name__ == "__main__":
    main()
