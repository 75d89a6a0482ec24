"""Persist trained language-alignment models under ``alignment/<model_hash>/model/``.

Layout (one ``staged_directory``: complete or absent)::

    alignment/<model_hash>/model/motion_aligner.npz   MotionAlignerState (trajectory encoder weights,
                                                      codebook prototypes, config, text-encoder name)
                                 _SUCCESS.json        manifest: key, training logs, metrics, provenance

``<model_hash>`` is the content key of the training inputs (the logs' content keys, the aligner config,
the text encoder and the stage version) computed by the caller. Per-scene language features live
beside it, under ``alignment/<model_hash>/scenes/`` (``storage.language_scenes``).
"""

from __future__ import annotations

import datetime
import logging
from collections.abc import Mapping
from typing import Any, Protocol

from storage.markers import intact_marker, mark_done, read_marker
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

ALIGNMENT_DIR = "alignment"
ALIGNER_FILE = "motion_aligner.npz"
MODEL_FORMAT = "simsplat.alignment.model"
MODEL_FORMAT_VERSION = 1


class SavableState(Protocol):
    """What ``write_aligner_model`` stores (``MotionAlignerState`` satisfies it)."""

    def save(self, path: str) -> None: ...


def model_dir(model_hash: str) -> str:
    """``alignment/<model_hash>/model``."""
    if not model_hash or not all(c in "0123456789abcdef" for c in model_hash):
        raise ValueError(f"alignment model hash must be lowercase hex, got {model_hash!r}")
    return join_relpath(ALIGNMENT_DIR, model_hash, "model")


def read_aligner_manifest(store: ArtifactStore, model_hash: str) -> dict[str, Any] | None:
    """The manifest of a complete stored model, or ``None`` when absent or incomplete."""
    marker = read_marker(store, model_dir(model_hash))
    return marker if marker is not None and marker.get("key") == model_hash else None


def write_aligner_model(
    store: ArtifactStore,
    model_hash: str,
    state: SavableState,
    *,
    metrics: Mapping[str, float] | None = None,
    provenance: Mapping[str, Any] | None = None,
    overwrite: bool = False,
) -> dict[str, Any]:
    """Store a trained motion aligner atomically; returns its manifest (the stored one when it exists
    and ``overwrite`` is False)."""
    rel = model_dir(model_hash)
    existing = None if overwrite else intact_marker(store, rel, model_hash)
    if existing is not None:
        logger.info("alignment model %s already stored, skipping write", store.uri(rel))
        return existing
    with store.staged_directory(rel) as tmp:
        path = join_relpath(tmp, ALIGNER_FILE)
        with store.local_path_for_write(path) as local:
            state.save(local)
        manifest = {
            "format": MODEL_FORMAT,
            "format_version": MODEL_FORMAT_VERSION,
            "files": {ALIGNER_FILE: store.size(path)},
            "metrics": {k: float(v) for k, v in (metrics or {}).items()},
            "written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds"),
            "provenance": dict(provenance or {}),
        }
        mark_done(store, tmp, model_hash, manifest)
    logger.info("wrote alignment model %s", store.uri(rel))
    return read_aligner_manifest(store, model_hash) or manifest


def read_aligner_state(store: ArtifactStore, model_hash: str):
    """The stored ``MotionAlignerState`` of ``model_hash``.

    Raises:
        FileNotFoundError: no complete model with that hash (naming the path).
        ValueError: the state file is of another layout version (naming the file).
    """
    from simsplat_core.language.alignment.motion_training import MotionAlignerState

    rel = model_dir(model_hash)
    if read_aligner_manifest(store, model_hash) is None:
        raise FileNotFoundError(f"{store.uri(rel)}: no complete alignment model")
    with store.local_path_for_read(join_relpath(rel, ALIGNER_FILE)) as local:
        return MotionAlignerState.load(local)


def list_aligner_models(store: ArtifactStore) -> list[str]:
    """Hashes of the complete stored models, newest first."""
    return [name for name, _ in stored_aligner_manifests(store)]


def stored_aligner_manifests(store: ArtifactStore) -> list[tuple[str, dict[str, Any]]]:
    """``(model_hash, manifest)`` of every complete stored model, newest first (each manifest read once)."""
    if not store.is_dir(ALIGNMENT_DIR):
        return []
    found = []
    for name in store.listdir(ALIGNMENT_DIR):
        try:
            manifest = read_aligner_manifest(store, name)
        except ValueError:
            continue
        if manifest is not None:
            found.append((str(manifest.get("written_at", "")), name, manifest))
    return [(name, manifest) for _, name, manifest in sorted(found, key=lambda f: f[:2], reverse=True)]
