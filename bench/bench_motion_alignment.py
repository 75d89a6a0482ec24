"""Benchmark: motion/location labeller agreement, aligner training time and motion grounding accuracy.

    .venv/bin/python bench/bench_motion_alignment.py [--train-seeds 10] [--test-seeds 10] [--agreement-seeds 20]

Writes ``bench/results/motion_alignment.json`` with

* E5 encode latency (uncached: a single query, a batch of 64 passages; median of repeats);
* labeller agreement with the synthetic world's captions and intended behaviours (``--agreement-seeds``
  seeds from 0), and the label distribution on the real AV2 sample;
* training time of ``MotionAligner.fit`` on ``--train-seeds`` annotation-only synthetic logs (seeds
  from 0; codebook encoding, sample building and training included);
* top-1 grounding accuracy on ``--test-seeds`` held-out synthetic seeds (from 1000) and on the AV2
  sample (against its auto-labels): zero-shot (trained on synthetic only, the AV2 log held out), in-store
  (trained on synthetic logs plus the whole AV2 log, as ``simsplat align`` trains on every stored log,
  real ones by their auto-labels) and on a held-out half of its objects after training on synthetic logs
  plus the other half (``split_objects``);
* plain vs realistic synthetic training (``realism``), mean and std over ``--realism-seeds`` aligner
  seeds: realistic copies of the synthetic logs (``REALISTIC``: boxes off the lane centre lines) plus
  synthetic logs as long as the AV2 one; AV2 zero-shot / in-store and synthetic held-out accuracy.

The AV2 part is skipped when ``--av2`` does not exist. Torch runs single-threaded inside the aligner.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import logging
import platform
import statistics
import time
from pathlib import Path

from simsplat_core.eval.motion import grounding_accuracy, labeller_agreement, split_objects
from simsplat_core.language.alignment.motion_dataset import RealismConfig
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
from simsplat_core.language.motion_labels import label_log
from simsplat_core.language.text import E5TextEncoder, default_text_encoder
from simsplat_core.world import WorldConfig, generate_log

logger = logging.getLogger("bench.motion_alignment")
DEFAULT_AV2 = Path(__file__).resolve().parents[2] / "shared" / "data" / "av2" / "sensor-log-7fab2350"


def e5_latency(repeats: int = 5) -> dict[str, float]:
    """Median seconds of uncached E5 calls (distinct texts every time, fresh cache)."""
    encoder = E5TextEncoder(cache_size=1)
    encoder.encode_queries(["warm-up"])
    single, batch = [], []
    for r in range(repeats):
        t0 = time.perf_counter()
        encoder.encode_queries([f"the {r}th red car turning left at the intersection"])
        single.append(time.perf_counter() - t0)
        texts = [f"passage {r}-{i}: a vehicle number {i} driving past a parked van" for i in range(64)]
        t0 = time.perf_counter()
        encoder.encode_passages(texts)
        batch.append(time.perf_counter() - t0)
    return {
        "single_query_s": round(statistics.median(single), 4),
        "batch64_passages_s": round(statistics.median(batch), 4),
    }


def synthetic_logs(seeds: range, frames: int | None = None) -> list:
    config = WorldConfig(render_images=False) if frames is None else WorldConfig(render_images=False, num_frames=frames)
    return [generate_log(seed, config) for seed in seeds]


def per_class(report) -> dict:
    """``class -> [queries, accuracy, oracle accuracy]``."""
    return {k: [n, round(a, 3), round(o, 3)] for k, (n, a, o) in sorted(report.per_class.items())}


def rounded(summary: dict) -> dict:
    return {k: round(v, 4) if isinstance(v, float) else v for k, v in summary.items()}


#: The synthetic-to-real training recipe compared against plain synthetic training: realistic copies whose
#: boxes sit off the lane centre lines like real tracks, plus synthetic logs as long as the real one.
REALISTIC = RealismConfig(copies=1, time_stretch=(1.0, 1.0), lateral_offset_m=0.8)


def _mean_std(values: list[float]) -> dict[str, float]:
    return {"mean": round(statistics.mean(values), 4), "std": round(statistics.pstdev(values), 4)}


def realism_comparison(train: list, test: list, av2, config: MotionAlignerConfig, encoder, args,
                       trained: tuple[MotionAligner, MotionAligner]) -> dict:
    """Plain vs realistic synthetic training, ``--realism-seeds`` aligner seeds each (the AV2 figures swing
    by several points between seeds: 36 motion queries, most classes with 1-3 objects).

    Realistic: ``REALISTIC`` copies of every synthetic log, plus ``--train-seeds`` synthetic logs of the
    real log's length (the clean 4 s logs are kept, so synthetic held-out accuracy is measured as before).
    ``trained``: the zero-shot and in-store aligners of ``config`` (plain, its seed) already fitted.
    """
    long_logs = synthetic_logs(range(100, 100 + args.train_seeds), frames=len(av2.timestamps_us))
    recipes = {
        "plain": (train, config),
        "realistic": ([*train, *long_logs],
                      dataclasses.replace(config, samples=dataclasses.replace(config.samples, realism=REALISTIC))),
    }
    out: dict = {"realism": dataclasses.asdict(REALISTIC), "long_logs": len(long_logs),
                 "long_log_frames": len(av2.timestamps_us), "seeds": args.realism_seeds}
    for name, (logs, recipe) in recipes.items():
        rows: dict[str, list[float]] = collections.defaultdict(list)
        for seed in range(args.realism_seeds):
            seeded = dataclasses.replace(recipe, seed=seed)
            if seeded == config:  # plain training at the default seed: fitted already
                zero, in_store = trained
            else:
                zero = MotionAligner.fit(logs, seeded, encoder)
                in_store = MotionAligner.fit([*logs, av2], seeded, encoder)
            for key, aligner, logs_ in (("av2_zero_shot", zero, [av2]), ("av2_in_store", in_store, [av2]),
                                        ("synthetic_held_out", zero, test)):
                summary = grounding_accuracy(aligner, logs_, encoder).summary()
                rows[f"{key}_motion"].append(summary["motion"])
                rows[f"{key}_location"].append(summary["location"])
        out[name] = {key: _mean_std(values) for key, values in rows.items()}
        logger.info("%s: %s", name, out[name])
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--train-seeds", type=int, default=10)
    parser.add_argument("--test-seeds", type=int, default=10)
    parser.add_argument("--agreement-seeds", type=int, default=20)
    parser.add_argument("--av2", type=Path, default=DEFAULT_AV2)
    parser.add_argument("--realism-seeds", type=int, default=3, help="aligner seeds of the realism comparison")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "motion_alignment.json")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    result: dict = {"machine": {"cpu": platform.processor() or platform.machine(), "python": platform.python_version()}}

    result["e5_latency"] = e5_latency()
    logger.info("E5 latency: %s", result["e5_latency"])

    t0 = time.perf_counter()
    agreement_logs = synthetic_logs(range(args.agreement_seeds))
    gen_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    agreement = labeller_agreement(agreement_logs)
    result["labeller_agreement"] = {
        "seeds": args.agreement_seeds,
        **rounded(agreement.summary()),
        "label_seconds_per_log": round((time.perf_counter() - t0) / args.agreement_seeds, 4),
        "confusion": {" | ".join(k): v for k, v in agreement.confusion.items()},
    }
    logger.info("labeller agreement: %s", result["labeller_agreement"])

    train = (
        agreement_logs[: args.train_seeds]
        if args.train_seeds <= args.agreement_seeds
        else synthetic_logs(range(args.train_seeds))
    )
    test = synthetic_logs(range(1000, 1000 + args.test_seeds))
    encoder = default_text_encoder()
    config = MotionAlignerConfig()
    aligner = MotionAligner.fit(train, config, encoder)
    result["training"] = {
        "train_seeds": args.train_seeds,
        "world_generation_s_per_log": round(gen_s / max(args.agreement_seeds, 1), 3),
        "fit_s": round(aligner.train_seconds, 2),
        "epochs": config.epochs,
        "loss_first_epoch": rounded(aligner.history[0]),
        "loss_last_epoch": rounded(aligner.history[-1]),
        "held_out_loss": rounded(aligner.evaluate_loss(test)),
    }
    logger.info("training: %s", result["training"])
    synth = grounding_accuracy(aligner, test, encoder)
    result["grounding_synthetic_held_out"] = {
        "test_seeds": f"1000..{999 + args.test_seeds}",
        **rounded(synth.summary()),
        "per_class": per_class(synth),
    }
    logger.info("grounding (synthetic held-out): %s", rounded(synth.summary()))

    if args.av2.is_dir():
        from simsplat_core.data.av2 import load_av2_log

        av2 = load_av2_log(args.av2)
        labels = label_log(av2)
        result["av2_labels"] = {
            "objects": len(labels),
            "motion": dict(collections.Counter(f"{lb.kind}:{lb.motion}" for lb in labels.values()).most_common()),
            "sector": dict(collections.Counter(lb.sector for lb in labels.values()).most_common()),
            "context": dict(collections.Counter(f"{lb.kind}:{lb.context}" for lb in labels.values()).most_common()),
        }
        zero_shot = grounding_accuracy(aligner, [av2], encoder)
        in_store_aligner = MotionAligner.fit([*train, av2], config, encoder)
        in_store = grounding_accuracy(in_store_aligner, [av2], encoder)
        half_a, half_b = split_objects(av2, seed=0)
        with_av2 = MotionAligner.fit([*train, half_a], config, encoder)
        held_out = grounding_accuracy(with_av2, [half_b], encoder)
        result["grounding_av2"] = {
            "log": args.av2.name,
            "zero_shot_trained_on_synthetic": rounded(zero_shot.summary()),
            "in_store_trained_with_av2": {
                **rounded(in_store.summary()),
                "fit_s": round(in_store_aligner.train_seconds, 2),
            },
            "held_out_half_trained_with_other_half": {
                **rounded(held_out.summary()),
                "fit_s": round(with_av2.train_seconds, 2),
            },
            "per_class_zero_shot": per_class(zero_shot),
            "per_class_in_store": per_class(in_store),
            "per_class_held_out_half": per_class(held_out),
        }
        logger.info("grounding (AV2): %s", result["grounding_av2"])
        result["realism"] = realism_comparison(train, test, av2, config, encoder, args,
                                               trained=(aligner, in_store_aligner))
        logger.info("realistic synthetic training: %s", result["realism"])
    else:
        logger.warning("AV2 sample not found at %s; skipping the AV2 part", args.av2)

    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    logger.info("wrote %s", args.out)


if __name__ == "__main__":
    main()
