"""Tasks that put driving logs into the artifact store: synthetic generation and real-log ingest.

Each task is thin: compute the content key of its inputs, skip if the store already holds a complete
log under that key, else load/generate with ``simsplat_core`` and write with ``storage``.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.summary import LogSummary, summarize_log
from simsplat_core.types import SceneLog
from simsplat_core.world import WORLD_VERSION, WorldConfig, default_seq_id, generate_log
from storage import (
    ArtifactStore,
    content_key,
    log_dir,
    manifest_bytes,
    read_log_manifest,
    read_scene_log,
    require_log_manifest,
    write_scene_log,
)
from storage.integrity import intact
from storage.markers import MARKER_NAME
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class StoredLog:
    """What a log-producing task returns (small: it crosses process boundaries).

    Attributes:
        summary: counts describing the log.
        relpath: where the log lives in the store (``logs/<seq_id>``).
        bytes_on_disk: total size of the log's files.
        seconds: wall time spent producing and writing it (0 when skipped).
        skipped: True when a complete log with the same content key was already stored.
    """

    summary: LogSummary
    relpath: str
    bytes_on_disk: int
    seconds: float
    skipped: bool


def _produced_before(store: ArtifactStore, seq_id: str, key: str) -> StoredLog | None:
    """The complete log ``seq_id`` when its producer stored it under ``key``, else ``None``."""
    manifest = read_log_manifest(store, seq_id)
    if manifest is not None and not intact(store, log_dir(seq_id), manifest, MARKER_NAME):
        manifest = None
    provenance = (manifest or {}).get("provenance", {})
    if manifest is not None and provenance.get("producer_key") == key and "summary" in provenance:
        return _already_stored(store, seq_id, manifest)
    return None


def _store_log(store: ArtifactStore, seq_id: str, key: str, produce: Callable[[], SceneLog]) -> StoredLog:
    relpath = log_dir(seq_id)
    stored = _produced_before(store, seq_id, key)
    if stored is not None:
        logger.info("%s: already stored for producer key %s, skipping", seq_id, key[:12])
        return stored
    started = time.perf_counter()
    log = produce()
    summary = summarize_log(log)
    written = write_scene_log(store, log, provenance={"producer_key": key, "summary": summary.to_dict()})
    seconds = time.perf_counter() - started
    logger.info("%s: wrote %d bytes in %.1f s", seq_id, written.bytes, seconds)
    return StoredLog(summary, relpath, written.bytes, round(seconds, 3), False)


def stored_log(store_root: str, seq_id: str) -> StoredLog:
    """The ``StoredLog`` of a log already in the store (``skipped``: nothing was produced now).

    The summary comes from the manifest's provenance when the producer recorded it (every log that
    ``generate_synthetic_log`` / ``ingest_real_log`` wrote), else from reading the log without pixels.

    Raises:
        FileNotFoundError: no complete log ``seq_id`` in the store (named).
    """
    store = ArtifactStore(store_root)
    return _already_stored(store, seq_id, require_log_manifest(store, seq_id))


def _already_stored(store: ArtifactStore, seq_id: str, manifest: dict) -> StoredLog:
    """The ``StoredLog`` of a complete log from its manifest (summary recorded by the producer, else read
    from the log without pixels, with the image count the manifest recorded)."""
    recorded = manifest.get("provenance", {}).get("summary")
    if recorded:
        summary = LogSummary(**recorded)
    else:
        read = summarize_log(read_scene_log(store, seq_id, load_images=False))
        summary = dataclasses.replace(read, num_images=int(manifest.get("images", {}).get("count", 0)))
    return StoredLog(summary, log_dir(seq_id), manifest_bytes(manifest), 0.0, True)


def _synthetic_key(seed: int, config: WorldConfig) -> str:
    return content_key("synthetic-log", WORLD_VERSION, seed, dataclasses.asdict(config))


def reusable_synthetic_log(store_root: str, seed: int, config: WorldConfig) -> StoredLog | None:
    """The synthetic log of ``seed`` when the store holds it as ``generate_synthetic_log`` would produce it now
    (same seed, world settings and version), else ``None``. Reads one manifest: the run planner asks it too."""
    return _produced_before(ArtifactStore(store_root), default_seq_id(seed), _synthetic_key(seed, config))


@task(name="generate-synthetic-log", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def generate_synthetic_log(store_root: str, seed: int, config: WorldConfig) -> StoredLog:
    """Generate the synthetic sequence of ``seed`` into ``<store>/logs/<seq_id>``."""
    seq_id = default_seq_id(seed)
    key = _synthetic_key(seed, config)
    return _store_log(
        ArtifactStore(store_root), seq_id, key, lambda: generate_log(seed=seed, config=config, seq_id=seq_id)
    )


@task(name="ingest-real-log", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def ingest_real_log(store_root: str, source: str, path: str, image_scale: float = 1.0) -> StoredLog:
    """Decode a real driving log with the loader ``source`` names in ``simsplat_core.data.registry`` (``"auto"``:
    the source that recognises ``path``) and store it.

    ``image_scale`` goes to sources that take it (``waymo-frame``); for the others it must stay 1. Decoding
    always runs (the seq_id comes from the file); the write is skipped when the store already holds an
    identical log.

    Raises:
        UnknownLogSourceError: an unknown source, or ``auto`` and a path no source recognises (both list the
            known sources).
        ValueError: ``image_scale != 1`` for a source without images to scale.
        CorruptLogError, FileNotFoundError: the loader's errors.
    """
    started = time.perf_counter()
    decoded = decode_real_log(source, path, image_scale)
    return store_real_log(store_root, decoded, started)


@dataclass(frozen=True)
class DecodedLog:
    """A real log decoded by its source's loader, not stored yet.

    Attributes:
        log: the decoded log.
        source: the registered source that loaded it.
        path: the file or folder it came from.
        image_scale: the image scale it was decoded at.
    """

    log: SceneLog
    source: str
    path: str
    image_scale: float


def decode_real_log(source: str, path: str, image_scale: float = 1.0) -> DecodedLog:
    """Decode ``path`` with the loader of ``source`` (``"auto"``: detected); see ``ingest_real_log``.

    Raises:
        UnknownLogSourceError, ValueError, CorruptLogError, FileNotFoundError: see ``ingest_real_log``.
    """
    from simsplat_core.data.registry import load_log, resolve_source

    chosen = resolve_source(source, path)
    options: dict[str, Any] = {"image_scale": image_scale} if "image_scale" in chosen.options else {}
    if not options and image_scale != 1.0:
        raise ValueError(f"log source {chosen.name!r} has no images to scale (image_scale {image_scale})")
    return DecodedLog(load_log(chosen.name, Path(path), **options), chosen.name, str(path), image_scale)


def store_real_log(store_root: str, decoded: DecodedLog, started: float) -> StoredLog:
    """Write a decoded real log into the store (skipped when an identical log is there); ``started`` is the
    ``time.perf_counter()`` when its decoding began (for the reported seconds)."""
    summary = summarize_log(decoded.log)
    provenance = {"source_path": decoded.path, "image_scale": decoded.image_scale, "summary": summary.to_dict()}
    written = write_scene_log(ArtifactStore(store_root), decoded.log, provenance=provenance)
    seconds = time.perf_counter() - started
    logger.info("%s: ingested from %s as %s (%d bytes, %.1f s)", decoded.log.seq_id, decoded.path, decoded.source,
                written.bytes, seconds)
    return StoredLog(summary, written.relpath, written.bytes, round(seconds, 3), written.skipped)
