"""Trajectory encoder + codebooks: convex features, training, grounding on a held-out log, persistence."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.language.alignment.motion_dataset import (
    RealismConfig,
    SampleConfig,
    TrainingSamples,
    build_samples,
    mirror_log,
    realistic_log,
)
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig, MotionAlignerState
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.motion_labels import label_log
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.vocabulary import LOCATION_CONTEXT, LOCATION_SECTOR, PEDESTRIAN_MOTION, VEHICLE_MOTION


def test_prototypes_are_unit_text_embeddings(aligner: MotionAligner, encoder) -> None:
    books = aligner.codebooks
    assert books.encoder_name == encoder.name
    for book, vocab in ((books.vehicle, VEHICLE_MOTION), (books.pedestrian, PEDESTRIAN_MOTION),
                        (books.sector, LOCATION_SECTOR), (books.context, LOCATION_CONTEXT)):
        assert book.classes == vocab.names
        assert book.prototypes.shape == (len(vocab), encoder.dim)
        np.testing.assert_allclose(np.linalg.norm(book.prototypes, axis=1), 1.0, atol=1e-5)
    phrase = encoder.encode_passages(list(VEHICLE_MOTION[voc.TURNING_LEFT].prototypes)).mean(axis=0)
    np.testing.assert_allclose(books.vehicle.prototypes[0], phrase / np.linalg.norm(phrase), atol=1e-6)


def test_features_are_convex_combinations_of_prototypes(aligner: MotionAligner, held_out_log) -> None:
    feats = aligner.features(held_out_log)
    movable = {o.object_id for o in held_out_log.objects if o.category in ("vehicle", "pedestrian")}
    assert set(feats) == movable
    books = aligner.codebooks
    for f in feats.values():
        w_mot = np.array(list(f.motion_probs.values()))
        w_loc = np.array(list(f.location_probs.values()))
        assert (w_mot >= 0).all() and (w_loc >= 0).all()
        assert w_mot.sum() == pytest.approx(1.0, abs=1e-5) and w_loc.sum() == pytest.approx(1.0, abs=1e-5)
        assert tuple(f.motion_probs) == books.motion(f.kind).classes
        np.testing.assert_allclose(f.f_mot, w_mot @ books.motion(f.kind).prototypes, atol=1e-5)
        np.testing.assert_allclose(f.f_loc, w_loc @ books.location_prototypes, atol=1e-5)
        assert f.f_mot.shape == f.f_loc.shape == (384,) and f.f_mot.dtype == np.float32


def test_training_reduces_the_loss(aligner: MotionAligner, held_out_log) -> None:
    first, last = aligner.history[0], aligner.history[-1]
    assert last["total"] < 0.3 * first["total"]
    assert last["mot"] < first["mot"] and last["loc"] < first["loc"]
    untrained = MotionAligner(
        aligner.config, aligner.codebooks, MotionAligner._new_network(aligner.config, aligner.codebooks)
    )
    assert aligner.evaluate_loss([held_out_log])["total"] < 0.5 * untrained.evaluate_loss([held_out_log])["total"]


QUERIES = {
    voc.TURNING_RIGHT: "the vehicle making a right at the junction",
    voc.TURNING_LEFT: "a car that takes a left turn",
    voc.PARKED: "a car left parked by the roadside",
    voc.STANDING: "a person who stands still",
    voc.WALKING_ALONG: "someone walking on the pavement",
}


def test_trained_aligner_ranks_the_right_object_first(aligner: MotionAligner, encoder, held_out_log) -> None:
    feats = aligner.features(held_out_log)
    kind_of = {c: "vehicle" for c in VEHICLE_MOTION.names} | {c: "pedestrian" for c in PEDESTRIAN_MOTION.names}
    checked = 0
    for cls, text in QUERIES.items():
        cands = {oid: f for oid, f in feats.items() if f.kind == kind_of[cls]}
        labels = [f.labels.motion for f in cands.values()]
        if cls not in labels or set(labels) == {cls}:
            continue
        mot_sim, _ = aligner.score(encoder.encode_queries([text])[0], cands)
        best = list(cands.values())[int(np.argmax(mot_sim))]
        assert best.labels.motion == cls, (text, best.object_id, best.motion_probs)
        checked += 1
    assert checked >= 3
    # a location query: the object most "ahead of me" among vehicles is in front of the ego
    vehicles = {oid: f for oid, f in feats.items() if f.kind == "vehicle"}
    _, loc_sim = aligner.score(encoder.encode_queries(["the car right ahead of us"])[0], vehicles)
    assert list(vehicles.values())[int(np.argmax(loc_sim))].labels.sector == voc.IN_FRONT_OF_EGO


def test_save_load_round_trip_gives_identical_features(aligner: MotionAligner, held_out_log, tmp_path) -> None:
    path = tmp_path / "aligner.npz"
    aligner.save(path)
    restored = MotionAligner.load(path)
    assert restored.config == aligner.config
    before, after = aligner.features(held_out_log), restored.features(held_out_log)
    assert before.keys() == after.keys()
    for oid in before:
        np.testing.assert_array_equal(before[oid].f_mot, after[oid].f_mot)
        np.testing.assert_array_equal(before[oid].f_loc, after[oid].f_loc)
        assert before[oid].motion_probs == after[oid].motion_probs
    state = MotionAlignerState.load(path)
    assert all(isinstance(v, np.ndarray) for v in {**state.weights, **state.prototypes}.values())


def test_score_checks_the_query_width(aligner: MotionAligner, held_out_log) -> None:
    with pytest.raises(ValueError, match="dims"):
        aligner.score(np.ones(10), aligner.features(held_out_log))


def test_training_is_deterministic_for_a_seed(train_logs, encoder) -> None:
    config = MotionAlignerConfig(epochs=2, seed=5)
    config = dataclasses.replace(config, samples=dataclasses.replace(config.samples, windows_per_track=1, mirror=False))
    a = MotionAligner.fit(train_logs[:1], config, encoder).state()
    b = MotionAligner.fit(train_logs[:1], config, encoder).state()
    for key in a.weights:
        np.testing.assert_array_equal(a.weights[key], b.weights[key])


def test_mirroring_swaps_left_and_right(train_logs) -> None:
    log = train_logs[0]
    def mirrored(name: str) -> str:
        return name.replace("left", "\0").replace("right", "left").replace("\0", "right")

    labels, flipped = label_log(log), label_log(mirror_log(log))
    for oid, lb in labels.items():
        assert flipped[oid].motion == mirrored(lb.motion)
        assert flipped[oid].sector == mirrored(lb.sector)


def test_codebooks_round_trip_through_arrays(aligner: MotionAligner) -> None:
    books = aligner.codebooks
    classes = {cb.name: cb.classes for cb in (books.vehicle, books.pedestrian, books.sector, books.context)}
    again = MotionCodebooks.from_arrays(books.encoder_name, classes, books.arrays())
    np.testing.assert_array_equal(again.location_prototypes, books.location_prototypes)
    np.testing.assert_array_equal(again.motion_centre, books.motion_centre)


def test_realistic_copy_stretches_time_jitters_and_thins_tracks(train_logs) -> None:
    log = train_logs[0]
    config = RealismConfig(time_stretch=(2.0, 2.0), position_noise_m=0.05, drop_rate=0.3)
    real = realistic_log(log, config, np.random.default_rng(0))
    assert real.images == () and real.map_features == log.map_features
    duration = lambda lg: (lg.timestamps_us[-1] - lg.timestamps_us[0]) * 1e-6  # noqa: E731
    assert duration(real) == pytest.approx(2.0 * duration(log), abs=1e-5)
    long = [(a, b) for a, b in zip(log.tracks, real.tracks) if len(a) > 20]
    assert long and all(len(b) < len(a) for a, b in long)  # interior frames dropped...
    for a, b in long:  # ...never the first or the last; centres jittered by centimetres
        assert (b.frame_idx[0], b.frame_idx[-1]) == (a.frame_idx[0], a.frame_idx[-1])
        rows = np.searchsorted(a.frame_idx, b.frame_idx)
        offsets = np.linalg.norm(b.center[:, :2] - a.center[rows, :2], axis=1)
        assert 0.0 < offsets.mean() < 0.2
        assert np.allclose(b.speed, a.speed[rows] / 2.0)


def test_realistic_copy_moves_each_track_sideways_off_its_lane_centre(train_logs) -> None:
    log = train_logs[0]
    config = RealismConfig(time_stretch=(1.0, 1.0), position_noise_m=0.0, heading_noise_rad=0.0, drop_rate=0.0,
                           lateral_offset_m=0.8)
    real = realistic_log(log, config, np.random.default_rng(3))
    offsets = []
    for a, b in zip(log.tracks, real.tracks):
        left = np.stack([-np.sin(a.heading), np.cos(a.heading)], axis=1)  # [T, 2] left normal of the box
        shift = b.center[:, :2] - a.center[:, :2]  # [T, 2]
        along = np.einsum("ij,ij->i", shift, np.stack([np.cos(a.heading), np.sin(a.heading)], axis=1))
        assert np.allclose(along, 0.0, atol=1e-9)  # sideways only...
        sideways = np.einsum("ij,ij->i", shift, left)
        assert np.allclose(sideways, sideways[0], atol=1e-9)  # ...by one offset per track
        offsets.append(sideways[0])
    assert len(set(np.round(offsets, 6))) == len(offsets)  # drawn per track
    assert 0.3 < np.std(offsets) < 1.6


def test_realism_adds_samples_for_synthetic_logs_only(train_logs, encoder) -> None:
    books = MotionCodebooks.build(encoder)
    config = MotionAlignerConfig()
    plain = build_samples(train_logs[:1], books, config.inputs, config.samples, config.thresholds, 0)
    realistic = dataclasses.replace(config.samples, realism=RealismConfig(copies=1))
    more = build_samples(train_logs[:1], books, config.inputs, realistic, config.thresholds, 0)
    assert isinstance(more, TrainingSamples) and len(more) > len(plain)
    real_source = dataclasses.replace(train_logs[0], source="av2")
    same = build_samples([real_source], books, config.inputs, realistic, config.thresholds, 0)
    assert len(same) == len(plain)


def test_config_with_realism_round_trips_through_json() -> None:
    config = MotionAlignerConfig(samples=SampleConfig(realism=RealismConfig(copies=2, time_stretch=(1.5, 2.5))))
    assert MotionAlignerConfig.from_json(config.to_json()) == config
    assert MotionAlignerConfig.from_json(MotionAlignerConfig().to_json()) == MotionAlignerConfig()
