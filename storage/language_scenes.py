"""Persist language-aligned scenes (``LanguageScene`` + fitted per-Gaussian features) and read them back.

Layout of one language scene (one ``staged_directory``: complete or absent)::

    alignment/<model_hash>/scenes/<seq_id>/<language_hash>/
        nodes.parquet          DESIGN's nodes table with real f_app / f_mot / f_loc (zeros where a node has
                               none; ``node_language.has_*`` says which)
        node_language.parquet  per object node: kind, caption, caption/motion details as JSON
        gaussians.parquet      the scene's Gaussians with ``feature[d]`` (fitted appearance latents), in the
                               scene graph's canonical order (absent for a log without camera images:
                               its scene is built from the log's tracks, no Gaussians)
        autoencoder.npz        the scene's feature autoencoder (``d -> D`` decoder for relevance maps)
        node_ids/<camera>/<frame_idx:06d>.exr   rendered node-id maps (channel ``id``; -1 = nothing)
        _SUCCESS.json          manifest: key, scene hash, frames, cameras, metrics, provenance

``<model_hash>`` names the motion aligner the features come from (``storage.alignment``);
``<language_hash>`` is the content key of (aligner, reconstructed scene -- or, without images, the log --,
alignment config, versions).
Node poses and deformations are not copied: they are read from the reconstructed scene
(``scenes/<seq_id>/<scene_hash>/``) the manifest names.
"""

from __future__ import annotations

import dataclasses
import datetime
import io
import json
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa

from simsplat_core.types import node_type_for_category
from storage.alignment import ALIGNMENT_DIR, model_dir
from storage.errors import CorruptArtifactError
from storage.exr import read_exr, render_channels, write_exr
from storage.markers import intact_marker, mark_done, read_marker
from storage.scenes import gaussian_columns, gaussians_table, nodes_table, read_scene
from storage.schemas.base import arrow_to_vectors
from storage.schemas.language import NODE_LANGUAGE_SCHEMA
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

LANGUAGE_FORMAT = "simsplat.language_scene"
LANGUAGE_FORMAT_VERSION = 1
AUTOENCODER_FILE = "autoencoder.npz"


def language_dir(model_hash: str, seq_id: str, language_hash: str) -> str:
    """``alignment/<model_hash>/scenes/<seq_id>/<language_hash>``."""
    base = model_dir(model_hash).rsplit("/", 1)[0]
    return join_relpath(base, "scenes", seq_id, language_hash)


def node_id_map_relpath(camera: str, frame_idx: int) -> str:
    return f"node_ids/{camera}/{int(frame_idx):06d}.exr"


def read_language_manifest(store: ArtifactStore, model_hash: str, seq_id: str, language_hash: str) -> dict | None:
    """The manifest of a complete language scene, or ``None``."""
    marker = read_marker(store, language_dir(model_hash, seq_id, language_hash))
    return marker if marker is not None and marker.get("key") == language_hash else None


# ----------------------------------------------------------------------------- JSON of core records
def caption_to_json(caption) -> str:
    """``AppearanceCaption`` -> JSON text (``""`` for ``None``)."""
    return "" if caption is None else json.dumps(dataclasses.asdict(caption), sort_keys=True)


def caption_from_json(text: str):
    from simsplat_core.language.appearance.captioner import AppearanceCaption

    if not text:
        return None
    data = json.loads(text)
    data["colors"] = tuple(data.get("colors", ()))
    return AppearanceCaption(**data)


def motion_to_json(motion) -> str:
    """``ObjectMotionFeatures`` less its vectors (stored in ``nodes``) -> JSON text (``""`` for ``None``)."""
    if motion is None:
        return ""
    return json.dumps({"object_id": motion.object_id, "kind": motion.kind, "motion_probs": motion.motion_probs,
                       "location_probs": motion.location_probs, "labels": dataclasses.asdict(motion.labels)},
                      sort_keys=True)


def motion_from_json(text: str, f_mot: np.ndarray, f_loc: np.ndarray):
    from simsplat_core.language.motion_labels import MotionLabel
    from simsplat_core.language.scene_language import ObjectMotionFeatures

    if not text:
        return None
    data = json.loads(text)
    return ObjectMotionFeatures(object_id=data["object_id"], kind=data["kind"], f_mot=f_mot, f_loc=f_loc,
                                motion_probs=data["motion_probs"], location_probs=data["location_probs"],
                                labels=MotionLabel(**data["labels"]))


# ----------------------------------------------------------------------------- write
def _feature_matrix(nodes, attribute: str, dim: int) -> np.ndarray:
    """``[len(nodes), dim]`` float32 rows of each node's ``attribute`` (zeros for ``None`` nodes or values)."""
    out = np.zeros((len(nodes), dim), np.float32)
    for i, node in enumerate(nodes):
        value = None if node is None else getattr(node, attribute)
        if value is not None:
            out[i] = np.asarray(value, np.float32).reshape(dim)
    return out


def _language_tables(scene_id: str, scene, scene_nodes: Sequence[Mapping[str, Any]], dim: int
                     ) -> dict[str, tuple[pa.Table, pa.Schema]]:
    """``nodes`` (every node of the scene, object rows with features) and ``node_language`` (object nodes)."""
    by_id = {n.node_id: n for n in scene.nodes}
    rows = [by_id.get(int(nd["node_id"])) for nd in scene_nodes]
    features = {name: _feature_matrix(rows, name, dim) for name in ("f_app", "f_mot", "f_loc")}
    language = pa.table({
        "scene_id": pa.array([scene_id] * len(scene.nodes), pa.string()),
        "node_id": pa.array([n.node_id for n in scene.nodes], pa.int32()),
        "object_id": pa.array([n.object_id for n in scene.nodes], pa.string()),
        "category": pa.array([n.category for n in scene.nodes], pa.string()),
        "kind": pa.array([n.kind for n in scene.nodes], pa.string()),
        "has_appearance": pa.array([n.f_app is not None for n in scene.nodes], pa.bool_()),
        "has_motion": pa.array([n.motion is not None for n in scene.nodes], pa.bool_()),
        "caption": pa.array(["" if n.caption is None else n.caption.text for n in scene.nodes], pa.string()),
        "caption_json": pa.array([caption_to_json(n.caption) for n in scene.nodes], pa.string()),
        "motion_json": pa.array([motion_to_json(n.motion) for n in scene.nodes], pa.string()),
    })
    return {"nodes": nodes_table(scene_id, scene_nodes, dim, features),
            "node_language": (language, NODE_LANGUAGE_SCHEMA)}


def _track_nodes(scene) -> list[dict[str, Any]]:
    """Node rows of a scene built from a log's tracks (no reconstruction): one per object node."""
    return [{"node_id": n.node_id, "node_type": node_type_for_category(n.category), "object_id": n.object_id,
             "category": n.category} for n in scene.nodes]


def write_language_scene(
    store: ArtifactStore,
    model_hash: str,
    language_hash: str,
    scene,
    records,
    *,
    autoencoder_state=None,
    metrics: Mapping[str, float] | None = None,
    provenance: Mapping[str, Any] | None = None,
    overwrite: bool = False,
) -> dict[str, Any]:
    """Write one language scene atomically; returns its manifest.

    Args:
        scene: the ``LanguageScene`` (its ``scene_hash`` names the reconstructed scene it came from).
        records: ``SceneRecords`` of the scene graph *with* the fitted per-Gaussian features; ``None`` for a
            scene built from a log without camera images (one node row per object node, no Gaussians).
        autoencoder_state: the scene autoencoder's ``AutoencoderState`` (``to_arrays``), if any.
    """
    rel = language_dir(model_hash, scene.seq_id, language_hash)
    existing = None if overwrite else intact_marker(store, rel, language_hash)
    if existing is not None:
        logger.info("language scene %s already stored, skipping write", store.uri(rel))
        return existing
    dim = len(next((n.f_app for n in scene.nodes if n.f_app is not None),
                   next((n.f_mot for n in scene.nodes if n.f_mot is not None), np.zeros(384))))
    if records is not None:
        scene_id = str(records.scene_id)
        tables = _language_tables(scene_id, scene, list(records.nodes), dim)
        tables["gaussians"] = gaussians_table(scene_id, records.gaussians)
    else:
        scene_id = f"{scene.seq_id}/log"
        tables = _language_tables(scene_id, scene, _track_nodes(scene), dim)
    with store.staged_directory(rel) as tmp:
        stats = {}
        for name, (table, schema) in tables.items():
            path = join_relpath(tmp, f"{name}.parquet")
            store.write_table(path, table, schema)
            stats[name] = {"rows": table.num_rows, "bytes": store.size(path)}
        if autoencoder_state is not None:
            buffer = io.BytesIO()
            np.savez(buffer, **autoencoder_state.to_arrays())
            store.write_bytes(join_relpath(tmp, AUTOENCODER_FILE), buffer.getvalue())
        maps = scene.node_id_maps
        if maps is not None:
            for fi, frame in enumerate(np.asarray(scene.frame_indices).tolist()):
                for ci, camera in enumerate(scene.cameras):
                    write_exr(store, join_relpath(tmp, node_id_map_relpath(camera, frame)),
                              render_channels(node_id=maps[fi, ci]))
        manifest = {
            "format": LANGUAGE_FORMAT,
            "format_version": LANGUAGE_FORMAT_VERSION,
            "seq_id": scene.seq_id,
            "scene_hash": scene.scene_hash,
            "model_hash": model_hash,
            "text_encoder": scene.text_encoder,
            "dim": dim,
            "frame_indices": [int(f) for f in np.asarray(scene.frame_indices).reshape(-1)],
            "cameras": list(scene.cameras),
            "has_node_id_maps": maps is not None,
            "has_autoencoder": autoencoder_state is not None,
            "metadata": {str(k): str(v) for k, v in scene.metadata.items()},
            "tables": stats,
            "metrics": {k: float(v) for k, v in (metrics or {}).items() if np.isfinite(v)},
            "written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds"),
            "provenance": dict(provenance or {}),
        }
        mark_done(store, tmp, language_hash, manifest)
    logger.info("wrote language scene %s (%d object nodes)", store.uri(rel), len(scene.nodes))
    return manifest


# ----------------------------------------------------------------------------- read
@dataclass(frozen=True, eq=False)
class LoadedLanguageScene:
    """A stored language scene read back.

    Attributes:
        scene: the ``LanguageScene``.
        records: ``SceneRecords`` of the reconstructed scene with the fitted features in ``gaussians``
            (``SceneGraph.from_records(records)`` renders feature maps).
        autoencoder: the scene's ``FeatureAutoencoder`` (``None`` when none was stored).
        model_hash, language_hash, relpath, manifest: where it came from.
    """

    scene: Any
    records: Any
    autoencoder: Any
    model_hash: str
    language_hash: str
    relpath: str
    manifest: dict[str, Any] = field(default_factory=dict)


def list_language_scenes(store: ArtifactStore, seq_id: str) -> list[tuple[str, str]]:
    """``(model_hash, language_hash)`` of every complete language scene of ``seq_id``, newest first."""
    found = []
    for model_hash in store.listdir(ALIGNMENT_DIR):
        base = join_relpath(ALIGNMENT_DIR, model_hash, "scenes", seq_id)
        for language_hash in store.listdir(base):
            manifest = read_marker(store, join_relpath(base, language_hash))
            if manifest is not None and manifest.get("key") == language_hash:
                found.append((manifest.get("written_at", ""), model_hash, language_hash))
    return [(m, h) for _, m, h in sorted(found, reverse=True)]


def read_language_scene(store: ArtifactStore, seq_id: str, model_hash: str | None = None,
                        language_hash: str | None = None, *, with_records: bool = True) -> LoadedLanguageScene:
    """Read a language scene (the newest of ``seq_id`` unless hashes are given).

    ``with_records=False`` reads the ``LanguageScene`` only (``records`` and ``autoencoder`` are ``None``):
    grounding needs nodes and node-id maps, not the Gaussians or the decoder.

    Raises:
        FileNotFoundError: none is stored (naming the place looked in).
        SchemaError, CorruptArtifactError: a file does not decode or validate (naming it).
    """
    from simsplat_core.language.appearance.autoencoder import AutoencoderState, FeatureAutoencoder
    from simsplat_core.language.scene_language import LanguageScene, NodeLanguage

    if model_hash is None or language_hash is None:
        candidates = [(m, h) for m, h in list_language_scenes(store, seq_id)
                      if (model_hash is None or m == model_hash) and (language_hash is None or h == language_hash)]
        if not candidates:
            raise FileNotFoundError(f"{store.uri(ALIGNMENT_DIR)}: no language scene of {seq_id!r} "
                                    f"(run the alignment stage: simsplat align / simsplat run)")
        model_hash, language_hash = candidates[0]
    rel = language_dir(model_hash, seq_id, language_hash)
    manifest = read_language_manifest(store, model_hash, seq_id, language_hash)
    if manifest is None:
        raise FileNotFoundError(f"{store.uri(rel)}: no complete language scene")
    nodes = store.read_table(join_relpath(rel, "nodes.parquet"), "nodes")
    language = store.read_table(join_relpath(rel, "node_language.parquet"), NODE_LANGUAGE_SCHEMA)
    vectors = {name: dict(zip(nodes.column("node_id").to_pylist(), arrow_to_vectors(nodes.column(name))))
               for name in ("f_app", "f_mot", "f_loc")}
    entries = []
    for row in language.to_pylist():
        nid = int(row["node_id"])
        if nid not in vectors["f_app"]:
            raise CorruptArtifactError(f"{store.uri(join_relpath(rel, 'node_language.parquet'))}: node {nid} "
                                       f"is missing from nodes.parquet")
        entries.append(NodeLanguage(
            node_id=nid, object_id=row["object_id"], category=row["category"], kind=row["kind"],
            f_app=vectors["f_app"][nid] if row["has_appearance"] else None,
            caption=caption_from_json(row["caption_json"]),
            motion=motion_from_json(row["motion_json"], vectors["f_mot"][nid], vectors["f_loc"][nid])
            if row["has_motion"] else None,
        ))
    frames = np.asarray(manifest.get("frame_indices", []), np.int64)
    cameras = tuple(manifest.get("cameras", []))
    maps = None
    if manifest.get("has_node_id_maps"):
        planes = [[read_exr(store, join_relpath(rel, node_id_map_relpath(c, f)))["id"] for c in cameras]
                  for f in frames.tolist()]
        maps = np.asarray(planes, np.float32).round().astype(np.int32)
    scene = LanguageScene(seq_id=seq_id, scene_hash=manifest.get("scene_hash", ""), nodes=tuple(entries),
                          frame_indices=frames, cameras=cameras, node_id_maps=maps,
                          text_encoder=manifest.get("text_encoder", ""), metadata=dict(manifest.get("metadata", {})))
    records = None
    if with_records and manifest.get("scene_hash"):
        records = read_scene(store, seq_id, manifest["scene_hash"]).records
        records.gaussians = gaussian_columns(store.read_table(join_relpath(rel, "gaussians.parquet"), "gaussians"))
    autoencoder = None
    if with_records and manifest.get("has_autoencoder"):
        with np.load(io.BytesIO(store.read_bytes(join_relpath(rel, AUTOENCODER_FILE))), allow_pickle=False) as data:
            autoencoder = FeatureAutoencoder(AutoencoderState.from_arrays({k: data[k] for k in data.files}))
    return LoadedLanguageScene(scene, records, autoencoder, model_hash, language_hash, rel, manifest)
