"""Task that reconstructs one stored driving log into a scene-graph Gaussian scene.

Thin, like ``tasks.logs``: compute the scene hash from the stored log's content key and the config,
skip when a complete scene with that hash is stored, else load the log, call
``simsplat_core.scene.reconstruct`` (reporting per-iteration progress) and write the scene with
``storage.scenes``.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.scene import ReconstructionConfig, reconstruct
from storage import (
    ArtifactStore,
    canonical,
    config_settings,
    content_key,
    intact_marker,
    read_scene_log,
    require_log_manifest,
)
from storage.scenes import (
    SCENE_FORMAT_VERSION,
    metrics_from_json,
    scene_dir,
    scene_id_for,
    write_scene,
)
from tasks.progress import StepProgress
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)

#: Version of the reconstruction stage; bump it to invalidate every stored scene.
SCENE_VERSION = "reconstruct-v1"


@dataclass(frozen=True)
class StoredScene:
    """What the reconstruct task returns (small: it crosses process boundaries).

    Attributes:
        seq_id: the reconstructed sequence.
        scene_hash: content key of (log, config, versions); the scene's directory name.
        relpath: ``scenes/<seq_id>/<scene_hash>``.
        metrics: ``name -> value`` (PSNR/SSIM on test frames, timings, counts).
        seconds: wall time spent reconstructing and writing (0 when skipped).
        skipped: True when a complete scene with this hash was already stored.
    """

    seq_id: str
    scene_hash: str
    relpath: str
    metrics: dict[str, float]
    seconds: float
    skipped: bool


#: Config fields that change how a run reports or how many cores it uses, never what it produces.
RUN_ONLY_FIELDS = ("progress_every", "eval_every", "num_threads")


def scene_hash(log_key: str, config: ReconstructionConfig) -> str:
    """Content key of a reconstruction: the stored log's content key, the config (less its run-only
    fields, so the same scene is found whatever the core count) and the versions."""
    return content_key(
        "reconstruct", SCENE_VERSION, SCENE_FORMAT_VERSION, log_key, config_settings(config, RUN_ONLY_FIELDS)
    )


def reusable_scene(store: ArtifactStore, seq_id: str, config: ReconstructionConfig) -> StoredScene | None:
    """The complete stored scene of ``seq_id`` under ``config`` (keyed by ``scene_hash``), ``None`` when
    ``reconstruct_scene`` has to reconstruct it. The stored files are checked against
    their manifest (``storage.markers.intact_marker``: a corrupt scene is recomputed); the run planner asks it too.

    Raises:
        FileNotFoundError: the store holds no complete log ``seq_id``.
    """
    log_key = require_log_manifest(store, seq_id, "to reconstruct")["key"]
    return _stored_scene(store, seq_id, scene_hash(log_key, config))


def _stored_scene(store: ArtifactStore, seq_id: str, key: str) -> StoredScene | None:
    """The complete, intact stored scene ``scenes/<seq_id>/<key>``, else ``None``."""
    existing = intact_marker(store, scene_dir(seq_id, key), key)
    if existing is None:
        return None
    return StoredScene(seq_id, key, scene_dir(seq_id, key), metrics_from_json(existing.get("metrics", {})), 0.0, True)


@task(name="reconstruct-scene", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def reconstruct_scene(store_root: str, seq_id: str, config: ReconstructionConfig) -> StoredScene:
    """Reconstruct ``<store>/logs/<seq_id>`` into ``<store>/scenes/<seq_id>/<scene_hash>``.

    Raises:
        FileNotFoundError: the store holds no complete log ``seq_id``.
    """
    store = ArtifactStore(store_root)
    log_manifest = require_log_manifest(store, seq_id, "to reconstruct")
    key = scene_hash(log_manifest["key"], config)
    stored = _stored_scene(store, seq_id, key)
    if stored is not None:
        logger.info("%s: scene %s already stored, skipping", seq_id, key[:12])
        return stored

    started = time.perf_counter()
    log = read_scene_log(store, seq_id)
    result = reconstruct(log, config, progress=StepProgress(f"reconstruct {seq_id}"))
    provenance = {
        "log_key": log_manifest["key"],
        "scene_version": SCENE_VERSION,
        "config": canonical(dataclasses.asdict(config)),
    }
    write_scene(
        store,
        seq_id,
        key,
        result.graph.to_records(scene_id_for(seq_id, key)),
        result.metrics,
        result.test_renders,
        provenance=provenance,
    )
    seconds = time.perf_counter() - started
    logger.info(
        "%s: reconstructed in %.1f s (test PSNR %.2f dB)",
        seq_id,
        seconds,
        result.metrics.get("psnr_test", float("nan")),
    )
    return StoredScene(seq_id, key, scene_dir(seq_id, key), {k: float(v) for k, v in result.metrics.items()},
                       round(seconds, 3), False)
