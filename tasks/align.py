"""Tasks of the language-alignment stage: train the motion/location aligner on stored logs, then align
each reconstructed scene (captions, appearance autoencoder, per-Gaussian features, motion features).

Thin like the other tasks: compute a content key, skip when the store already holds the result, else
call ``simsplat_core.language`` and write through ``storage``.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.compute_threads import set_compute_threads
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import AlignmentConfig, build_language_scene
from simsplat_core.language.appearance.embedders import appearance_embedder
from simsplat_core.language.text import default_text_encoder
from simsplat_core.scene import SceneGraph
from storage import (
    ArtifactStore,
    canonical,
    config_settings,
    content_key,
    intact_marker,
    read_scene,
    read_scene_log,
    require_log_manifest,
)
from storage.alignment import (
    model_dir,
    read_aligner_state,
    stored_aligner_manifests,
    write_aligner_model,
)
from storage.integrity import intact
from storage.language_scenes import language_dir, write_language_scene
from storage.markers import MARKER_NAME
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)

#: Version of the aligner-training stage; bump it to invalidate every stored model.
ALIGNER_VERSION = "motion-aligner-v1"
#: Version of the scene-alignment stage; bump it to invalidate every stored language scene.
LANGUAGE_VERSION = "language-scene-v1"
#: A stored aligner (same config, text encoder and version) is reused while the logs it was trained on make up at
#: least this share of the logs asked for: a store that grows by a few logs a night retrains it (and so re-aligns
#: every scene, whose key holds the aligner's) only each time it has grown by half, not on every new log.
ALIGNER_REUSE_SHARE = 2 / 3


@dataclass(frozen=True)
class StoredAligner:
    """What ``train_motion_aligner`` returns (small: it crosses process boundaries).

    Attributes:
        model_hash: content key of (training logs, config, text encoder, version).
        relpath: ``alignment/<model_hash>/model``.
        seq_ids: the logs it was trained on.
        metrics: training figures (samples, final loss, seconds).
        seconds: wall time spent (0 when skipped).
        skipped: True when the model was already stored.
    """

    model_hash: str
    relpath: str
    seq_ids: tuple[str, ...]
    metrics: dict[str, float]
    seconds: float
    skipped: bool


def aligner_hash(log_keys: list[str], config: MotionAlignerConfig, encoder_name: str) -> str:
    """Content key of an aligner: the training logs' keys (order-free), config, encoder, version."""
    return content_key("align-model", ALIGNER_VERSION, sorted(log_keys), config.to_json(), encoder_name)


def _training_logs(store: ArtifactStore, seq_ids: list[str]) -> list[dict]:
    return [require_log_manifest(store, seq_id, "to train the aligner on") for seq_id in seq_ids]


def covering_aligner(store: ArtifactStore, log_sources: Mapping[str, str], config: MotionAlignerConfig,
                     encoder_name: str, share: float = ALIGNER_REUSE_SHARE) -> tuple[str, dict] | None:
    """The stored aligner of ``config`` and ``encoder_name`` whose training logs cover the largest part (at least
    ``share``) of the logs ``log_sources`` (content key -> source), and among them a log of every source (the first
    log of a new source, e.g. a real one in a synthetic store, gets an aligner trained on it); newest first among
    equals; ``None`` when none does. Its ``(model_hash, manifest)``."""
    wanted = set(log_sources)
    sources = set(log_sources.values())
    best: tuple[float, str, dict] | None = None
    for model_hash, manifest in stored_aligner_manifests(store):  # newest first: a tie keeps the newer one
        provenance = manifest.get("provenance", {})
        if (provenance.get("version") != ALIGNER_VERSION or provenance.get("config") != config.to_json()
                or provenance.get("text_encoder") != encoder_name):
            continue
        covered_keys = wanted & set(provenance.get("log_keys", []))
        covered = len(covered_keys) / len(wanted)
        if covered < share or {log_sources[k] for k in covered_keys} != sources:
            continue
        if best is None or covered > best[0]:
            best = (covered, model_hash, manifest)
    return None if best is None else (best[1], best[2])


def reusable_aligner(store: ArtifactStore, seq_ids: list[str], config: MotionAlignerConfig, encoder_name: str,
                     reuse_share: float = ALIGNER_REUSE_SHARE) -> StoredAligner | None:
    """The stored aligner that ``train_motion_aligner`` would reuse for ``seq_ids``: the one trained on exactly these
    logs (keyed by ``aligner_hash``), else the one ``covering_aligner`` finds; ``None`` when it has to train one. The
    stored files are checked against their manifest (``storage.markers.intact_marker``: a corrupt one is not
    reused); the run planner asks it too.

    Raises:
        FileNotFoundError: a log is missing from the store (named).
    """
    return _reusable_aligner(store, seq_ids, _training_logs(store, seq_ids), config, encoder_name, reuse_share)


def _reusable_aligner(store: ArtifactStore, seq_ids: list[str], manifests: list[dict], config: MotionAlignerConfig,
                      encoder_name: str, reuse_share: float) -> StoredAligner | None:
    """``reusable_aligner`` given the manifests of the logs ``seq_ids`` (``_training_logs``)."""
    key = aligner_hash([str(m["key"]) for m in manifests], config, encoder_name)
    existing = intact_marker(store, model_dir(key), key)
    if existing is not None:
        return StoredAligner(key, model_dir(key), tuple(seq_ids), dict(existing.get("metrics", {})), 0.0, True)
    covering = covering_aligner(store, {str(m["key"]): str(m.get("source", "")) for m in manifests}, config,
                                encoder_name, reuse_share)
    if covering is None:
        return None
    model_hash, manifest = covering
    if not intact(store, model_dir(model_hash), manifest, MARKER_NAME):
        return None
    trained_on = tuple(manifest.get("provenance", {}).get("seq_ids", ()))
    return StoredAligner(model_hash, model_dir(model_hash), trained_on, dict(manifest.get("metrics", {})), 0.0, True)


@task(name="train-motion-aligner", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def train_motion_aligner(store_root: str, seq_ids: list[str], config: MotionAlignerConfig | None = None,
                         reuse_share: float = ALIGNER_REUSE_SHARE) -> StoredAligner:
    """Train the motion/location aligner on the stored logs ``seq_ids`` (auto-labelled trajectories), unless a
    stored one (same config and text encoder) was trained on logs that make up at least ``reuse_share`` of them,
    of every source among them (``reusable_aligner``; 1.0: only one trained on exactly these logs). A reused
    aligner is returned as skipped, with the logs it was trained on.

    Raises:
        FileNotFoundError: a log is missing from the store (named).
        ValueError: ``seq_ids`` is empty.
    """
    if not seq_ids:
        raise ValueError("train_motion_aligner: no logs to train on")
    config = config or MotionAlignerConfig()
    store = ArtifactStore(store_root)
    encoder = default_text_encoder()
    manifests = _training_logs(store, seq_ids)
    keys = [str(m["key"]) for m in manifests]
    stored = _reusable_aligner(store, seq_ids, manifests, config, encoder.name, reuse_share)
    if stored is not None:
        logger.info("motion aligner %s (trained on %d of these %d logs) reused", stored.model_hash[:12],
                    len(set(stored.seq_ids) & set(seq_ids)), len(seq_ids))
        return stored
    key = aligner_hash(keys, config, encoder.name)
    started = time.perf_counter()
    logs = [read_scene_log(store, seq_id, load_images=False) for seq_id in seq_ids]
    aligner = MotionAligner.fit(logs, config, encoder)
    final = aligner.history[-1] if aligner.history else {}
    metrics = {"train_seconds": float(aligner.train_seconds), "logs": float(len(logs)),
               **{f"final_{k}": float(v) for k, v in final.items() if isinstance(v, (int, float))}}
    provenance = {"seq_ids": list(seq_ids), "log_keys": keys, "config": config.to_json(), "text_encoder": encoder.name,
                  "version": ALIGNER_VERSION}
    write_aligner_model(store, key, aligner.state(), metrics=metrics, provenance=provenance)
    seconds = time.perf_counter() - started
    logger.info("trained motion aligner %s on %d logs in %.1f s", key[:12], len(logs), seconds)
    return StoredAligner(key, model_dir(key), tuple(seq_ids), metrics, round(seconds, 3), False)


def load_motion_aligner(store: ArtifactStore, model_hash: str) -> MotionAligner:
    """The stored aligner ``model_hash`` (raises ``FileNotFoundError`` naming the path when absent)."""
    return MotionAligner.from_state(read_aligner_state(store, model_hash))


@dataclass(frozen=True)
class StoredLanguageScene:
    """What ``align_scene`` returns.

    Attributes:
        seq_id, scene_hash: the reconstructed scene that was aligned (``scene_hash`` ``""``: a log without
            camera images, aligned from its tracks and map).
        model_hash: the motion aligner used.
        language_hash: content key of (aligner, scene, config, version); the directory name.
        relpath: ``alignment/<model_hash>/scenes/<seq_id>/<language_hash>``.
        metrics: stage times, counts, fit and mask-agreement figures.
        seconds: wall time (0 when skipped).
        skipped: True when already stored.
    """

    seq_id: str
    scene_hash: str
    model_hash: str
    language_hash: str
    relpath: str
    metrics: dict[str, float]
    seconds: float
    skipped: bool


#: AlignmentConfig fields that never change what is stored.
RUN_ONLY_ALIGNMENT_FIELDS = ("eval_views", "measure_masks")


def language_hash(model_hash: str, scene_hash: str, config: AlignmentConfig, encoder_name: str,
                  embedder_name: str = "") -> str:
    """Content key of one aligned scene (the embedder's name carries e.g. the VLM model captioning it)."""
    return content_key("align-scene", LANGUAGE_VERSION, model_hash, scene_hash,
                       config_settings(config, RUN_ONLY_ALIGNMENT_FIELDS), encoder_name, embedder_name)


def _log_key(store: ArtifactStore, seq_id: str) -> str:
    return str(require_log_manifest(store, seq_id, "to align")["key"])


def _scene_language_hash(log_key: str, scene_hash: str | None, model_hash: str, config: AlignmentConfig,
                         encoder_name: str, embedder_name: str) -> str:
    """``language_hash`` of a reconstructed scene, or of a log without images (keyed by its log's content key)."""
    return language_hash(model_hash, scene_hash if scene_hash is not None else f"log-{log_key}", config, encoder_name,
                         embedder_name)


def reusable_language_scene(store: ArtifactStore, seq_id: str, scene_hash: str | None, model_hash: str,
                            config: AlignmentConfig, encoder_name: str, embedder_name: str
                            ) -> StoredLanguageScene | None:
    """The stored language scene that ``align_scene`` would reuse (``scene_hash`` ``None``: a log without images),
    ``None`` when it has to align. The stored files are checked against their manifest
    (``storage.markers.intact_marker``: a corrupt one is recomputed); the run planner asks it too.

    Raises:
        FileNotFoundError: the log is missing from the store (named).
    """
    key = _scene_language_hash(_log_key(store, seq_id), scene_hash, model_hash, config, encoder_name, embedder_name)
    return _stored_language_scene(store, seq_id, scene_hash, model_hash, key)


def _stored_language_scene(store: ArtifactStore, seq_id: str, scene_hash: str | None, model_hash: str, key: str
                           ) -> StoredLanguageScene | None:
    """The complete, intact stored language scene ``key`` of ``seq_id`` under aligner ``model_hash``, else ``None``."""
    existing = intact_marker(store, language_dir(model_hash, seq_id, key), key)
    if existing is None:
        return None
    return StoredLanguageScene(seq_id, scene_hash or "", model_hash, key, language_dir(model_hash, seq_id, key),
                               dict(existing.get("metrics", {})), 0.0, True)


@task(name="align-scene", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def align_scene(store_root: str, seq_id: str, scene_hash: str | None, model_hash: str,
                config: AlignmentConfig | None = None, threads: int = 0) -> StoredLanguageScene:
    """Build and store the language scene of ``scenes/<seq_id>/<scene_hash>`` with aligner ``model_hash``.

    Args:
        scene_hash: the reconstructed scene; ``None`` for a log without camera images, aligned straight
            from the log (object nodes from its tracks: motion and location language, no appearance, no
            Gaussians); its language hash is keyed by the log's content key instead.
        threads: torch/numba threads for this task (0 = leave the process setting).

    Raises:
        FileNotFoundError: the log, scene or aligner is missing (named).
        ValueError: ``scene_hash`` is ``None`` but the log has images (build_language_scene's check).
    """
    config = (config or AlignmentConfig()).validate()
    store = ArtifactStore(store_root)
    encoder = default_text_encoder()
    embedder = appearance_embedder(config.captioner, encoder)
    log_key = _log_key(store, seq_id)
    key = _scene_language_hash(log_key, scene_hash, model_hash, config, encoder.name, embedder.name)
    stored = _stored_language_scene(store, seq_id, scene_hash, model_hash, key)
    if stored is not None:
        logger.info("%s: language scene %s already stored, skipping", seq_id, key[:12])
        return stored
    relpath = language_dir(model_hash, seq_id, key)
    if threads:
        set_compute_threads(threads)
    started = time.perf_counter()
    aligner = load_motion_aligner(store, model_hash)
    log = read_scene_log(store, seq_id)
    graph, scene_id = None, ""
    if scene_hash is not None:
        loaded = read_scene(store, seq_id, scene_hash)
        scene_hash, scene_id = loaded.scene_hash, loaded.records.scene_id
        graph = SceneGraph.from_records(loaded.records)
    built = build_language_scene(graph, log, text_encoder=encoder, aligner=aligner, embedder=embedder, config=config,
                                 scene_hash=scene_hash or "")
    records = built.graph.to_records(scene_id) if built.graph is not None else None  # with the fitted features
    provenance = {"scene_hash": scene_hash or "", "log_key": log_key, "model_hash": model_hash,
                  "version": LANGUAGE_VERSION, "config": canonical(dataclasses.asdict(config)),
                  "text_encoder": encoder.name, "embedder": embedder.name}
    write_language_scene(store, model_hash, key, built.scene, records,
                         autoencoder_state=None if built.autoencoder is None else built.autoencoder.state(),
                         metrics=built.metrics, provenance=provenance)
    seconds = time.perf_counter() - started
    logger.info("%s: aligned %s in %.1f s", seq_id, f"scene {scene_hash[:12]}" if scene_hash else "log (no images)",
                seconds)
    return StoredLanguageScene(seq_id, scene_hash or "", model_hash, key, relpath,
                               {k: float(v) for k, v in built.metrics.items()}, round(seconds, 3), False)
