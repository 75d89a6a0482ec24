"""Persist ``SceneLog``s under ``logs/<seq_id>/`` and read them back.

Layout of one log (written inside one ``staged_directory``, so it appears complete or not at all)::

    logs/<seq_id>/frames.parquet          one row per CameraImage, in log order
                  ego_poses.parquet       one row per frame (annotation-only logs have no frames)
                  tracks.parquet          one row per (object, frame), tracks in log order
                  objects.parquet         one row per ObjectInfo, in log order
                  map_features.parquet    one row per MapFeature, in log order
                  images/<camera>/<frame_idx:06d>.exr   R,G,B (+ Z from depth, id from instance, mask from valid_mask)
                  _SUCCESS.json           manifest: content key, row counts, bytes, source, metadata

``frames.image_uri`` is the EXR path *relative to the log directory* (``images/front/000003.exr``), or
``""`` when the camera image has no pixel data at all (image, depth and instance all ``None``).

Precision: arrays are stored as float32 (see ``storage.schemas``) and read back as the dtypes of
``simsplat_core.types`` (float64 poses, boxes and points; int64 indices; float32 images and depth;
int32 instance ids). float64 inputs are therefore rounded to float32 once; inputs that are
float32-representable round-trip exactly. Instance ids go through the float32 EXR ``id`` channel and
are exact up to ``2**24``.

A log directory without ``_SUCCESS.json`` is incomplete and treated as absent.
"""

from __future__ import annotations

import datetime
import logging
import re
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from simsplat_core.types import CameraImage, MapFeature, ObjectInfo, SceneLog, Track
from storage.exr import MASK_CHANNEL, read_exr, render_channels, write_exr
from storage.integrity import require_intact
from storage.keys import content_key
from storage.markers import MARKER_NAME, is_done, mark_done, read_marker
from storage.schemas.base import arrow_to_vectors, schema_name, schema_version, vectors_to_arrow
from storage.schemas.logs import EGO_POSES_SCHEMA, FRAMES_SCHEMA, MAP_FEATURES_SCHEMA, OBJECTS_SCHEMA, TRACKS_SCHEMA
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

LOGS_DIR = "logs"
IMAGES_DIR = "images"
MANIFEST_FORMAT = "simsplat.scene_log"
MANIFEST_VERSION = 1
LOG_TABLES: dict[str, pa.Schema] = {
    schema_name(s): s for s in (FRAMES_SCHEMA, EGO_POSES_SCHEMA, TRACKS_SCHEMA, OBJECTS_SCHEMA, MAP_FEATURES_SCHEMA)
}
_SAFE_NAME = re.compile(r"^[A-Za-z0-9_\-][A-Za-z0-9_.\-]*$")


def _check_name(kind: str, value: str) -> str:
    if not _SAFE_NAME.match(value or ""):
        raise ValueError(
            f"{kind} {value!r} is not safe as a directory name (letters, digits, '_', '-', '.'; not leading '.')"
        )
    return value


def log_dir(seq_id: str) -> str:
    """Relative directory of a log: ``logs/<seq_id>``."""
    return join_relpath(LOGS_DIR, _check_name("seq_id", seq_id))


def image_uri(image: CameraImage) -> str:
    """Relative EXR path of a camera image inside its log directory, ``""`` when it has no pixels."""
    if image.image is None and image.depth is None and image.instance is None:
        return ""
    return _image_relpath(image.camera, image.frame_idx)


def _image_relpath(camera: str, frame_idx: int) -> str:
    """``images/<camera>/<frame>.exr`` inside a log directory."""
    return f"{IMAGES_DIR}/{_check_name('camera', camera)}/{int(frame_idx):06d}.exr"


def _rgb(channels: dict[str, np.ndarray]) -> np.ndarray | None:
    """``[H, W, 3]`` from an EXR's R, G, B channels (``None`` without them)."""
    return np.stack([channels[c] for c in "RGB"], axis=-1) if all(c in channels for c in "RGB") else None


def scene_log_key(log: SceneLog) -> str:
    """Content key of a log (every field, pixels included) and of this storage format."""
    return content_key(MANIFEST_FORMAT, MANIFEST_VERSION, log)


# ----------------------------------------------------------------------------- write
@dataclass(frozen=True)
class WrittenLog:
    """Outcome of ``write_scene_log``.

    Attributes:
        relpath: ``logs/<seq_id>``.
        key: content key of the log (``scene_log_key``).
        bytes: total size of the log's tables and images in the store.
        skipped: True when an identical complete log was already stored.
    """

    relpath: str
    key: str
    bytes: int
    skipped: bool


def manifest_bytes(manifest: dict) -> int:
    """Total bytes of a log's tables and images, from its manifest."""
    tables = manifest.get("tables", {})
    return int(sum(t.get("bytes", 0) for t in tables.values()) + manifest.get("images", {}).get("bytes", 0))


def read_log_manifest(store: ArtifactStore, seq_id: str) -> dict | None:
    """The ``_SUCCESS.json`` manifest of a complete log, or ``None`` when there is none."""
    return read_marker(store, log_dir(seq_id))


def require_log_manifest(store: ArtifactStore, seq_id: str, purpose: str = "") -> dict:
    """``read_log_manifest`` of a log that must be there.

    Raises:
        FileNotFoundError: no complete log ``seq_id`` (naming its place and, when given, ``purpose``:
            "to reconstruct", "to align", ...).
    """
    manifest = read_log_manifest(store, seq_id)
    if manifest is None:
        why = f" {purpose}" if purpose else ""
        raise FileNotFoundError(f"{store.uri(log_dir(seq_id))}: no complete scene log{why}")
    return manifest


def write_scene_log(
    store: ArtifactStore, log: SceneLog, *, overwrite: bool = False, provenance: dict | None = None
) -> WrittenLog:
    """Write ``log`` atomically under ``logs/<seq_id>/``.

    Skips the write when a complete log with the same content key is already there (unless
    ``overwrite``); replaces an older, different version only once the new one is complete.

    Args:
        provenance: JSON-serialisable facts about how the log was produced (e.g. the producer's
            own input key, so a producer can skip regenerating); stored in the manifest.

    Raises:
        LogValidationError: the log violates the data model (nothing is written).
        ValueError: unsafe seq_id / camera names or duplicate (camera, frame) images.
    """
    log.validate()
    rel = log_dir(log.seq_id)
    uris = [image_uri(img) for img in log.images]
    named = [u for u in uris if u]
    if len(set(named)) != len(named):
        raise ValueError(f"{log.seq_id}: duplicate (camera, frame_idx) images")
    key = scene_log_key(log)
    if not overwrite and is_done(store, rel, key):
        logger.info("scene log %s unchanged (key %s), skipping write", store.uri(rel), key[:12])
        return WrittenLog(rel, key, manifest_bytes(read_marker(store, rel) or {}), True)

    tables = {
        "frames": _frames_table(log, uris),
        "ego_poses": _ego_poses_table(log),
        "tracks": _tracks_table(log),
        "objects": _objects_table(log),
        "map_features": _map_features_table(log),
    }
    with store.staged_directory(rel) as tmp:
        table_stats = {}
        for name, table in tables.items():
            path = join_relpath(tmp, f"{name}.parquet")
            store.write_table(path, table, LOG_TABLES[name])
            table_stats[name] = {
                "rows": table.num_rows,
                "bytes": store.size(path),
                "schema_version": schema_version(LOG_TABLES[name]),
            }
        image_bytes = 0
        for img, uri in zip(log.images, uris):
            if uri:
                path = join_relpath(tmp, uri)
                write_exr(store, path, render_channels(
                    rgb=img.image, depth=img.depth, node_id=img.instance, valid_mask=img.valid_mask))
                image_bytes += store.size(path)
        manifest = {
            "format": MANIFEST_FORMAT,
            "format_version": MANIFEST_VERSION,
            "seq_id": log.seq_id,
            "source": log.source,
            "metadata": dict(log.metadata),
            "num_frames": log.num_frames,
            "cameras": list(log.cameras),
            "tables": table_stats,
            "images": {"count": len(named), "bytes": image_bytes},
            "written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "provenance": dict(provenance or {}),
        }
        mark_done(store, tmp, key, manifest)
    logger.info("wrote scene log %s (%d frames, %d images)", store.uri(rel), log.num_frames, len(named))
    return WrittenLog(rel, key, manifest_bytes(manifest), False)


def _strings(value: str, n: int) -> pa.Array:
    return pa.array([value] * n, pa.string())


def _frames_table(log: SceneLog, uris: list[str]) -> pa.Table:
    imgs = log.images
    n = len(imgs)
    return pa.table(
        {
            "seq_id": _strings(log.seq_id, n),
            "frame_idx": pa.array([img.frame_idx for img in imgs], pa.int64()),
            "timestamp_us": pa.array([img.timestamp_us for img in imgs], pa.int64()),
            "camera": pa.array([img.camera for img in imgs], pa.string()),
            "image_uri": pa.array(uris, pa.string()),
            "K": vectors_to_arrow(np.array([np.asarray(img.K).reshape(9) for img in imgs]).reshape(n, 9), 9),
            "cam_to_world": vectors_to_arrow(
                np.array([np.asarray(img.cam_to_world).reshape(16) for img in imgs]).reshape(n, 16), 16
            ),
            "width": pa.array([img.width for img in imgs], pa.int32()),
            "height": pa.array([img.height for img in imgs], pa.int32()),
            "split": pa.array([img.split for img in imgs], pa.string()),
        }
    )


def _ego_poses_table(log: SceneLog) -> pa.Table:
    f = log.num_frames
    return pa.table(
        {
            "seq_id": _strings(log.seq_id, f),
            "frame_idx": pa.array(np.arange(f, dtype=np.int64)),
            "timestamp_us": pa.array(np.asarray(log.timestamps_us, dtype=np.int64)),
            "ego_to_world": vectors_to_arrow(np.asarray(log.ego_poses).reshape(f, 16), 16),
        }
    )


def _tracks_table(log: SceneLog) -> pa.Table:
    tracks = log.tracks
    category = {obj.object_id: obj.category for obj in log.objects}
    lengths = [len(tr) for tr in tracks]
    n = sum(lengths)
    row_ids = [tr.object_id for tr, k in zip(tracks, lengths) for _ in range(k)]  # [n]

    def cat(attr: str, dtype: type, width: int | None = None) -> np.ndarray:
        shape = (0, width) if width else (0,)
        parts: list[np.ndarray] = [np.asarray(getattr(tr, attr), dtype=dtype) for tr in tracks]
        return np.concatenate(parts) if parts else np.zeros(shape, dtype)

    return pa.table(
        {
            "seq_id": _strings(log.seq_id, n),
            "object_id": pa.array(row_ids, pa.string()),
            "frame_idx": pa.array(cat("frame_idx", np.int64), pa.int64()),
            "category": pa.array([category[oid] for oid in row_ids], pa.string()),
            "center": vectors_to_arrow(cat("center", np.float64, 3), 3),
            "size": vectors_to_arrow(cat("size", np.float64, 3), 3),
            "heading": pa.array(cat("heading", np.float32), pa.float32()),
            "speed": pa.array(cat("speed", np.float32), pa.float32()),
            "visible": pa.array(cat("visible", np.bool_), pa.bool_()),
        }
    )


def _objects_table(log: SceneLog) -> pa.Table:
    objs = log.objects
    return pa.table(
        {
            "seq_id": _strings(log.seq_id, len(objs)),
            "object_id": pa.array([o.object_id for o in objs], pa.string()),
            "category": pa.array([o.category for o in objs], pa.string()),
            "node_type": pa.array([o.node_type for o in objs], pa.string()),
            "instance_id": pa.array([o.instance_id for o in objs], pa.int32()),
            "caption": pa.array([o.caption for o in objs], pa.string()),
            "attributes": pa.array([list(o.attributes.items()) for o in objs], pa.map_(pa.string(), pa.string())),
        }
    )


def _map_features_table(log: SceneLog) -> pa.Table:
    feats = log.map_features
    counts = [len(f.points) for f in feats]
    offsets = pa.array(np.concatenate([[0], np.cumsum(counts)]).astype(np.int32))
    points = [np.asarray(f.points, dtype=np.float64).reshape(-1, 3) for f in feats]
    values = vectors_to_arrow(np.concatenate(points) if points else np.zeros((0, 3)), 3)
    return pa.table(
        {
            "seq_id": _strings(log.seq_id, len(feats)),
            "feature_id": pa.array([f.feature_id for f in feats], pa.string()),
            "kind": pa.array([f.kind for f in feats], pa.string()),
            "points": pa.ListArray.from_arrays(offsets, values),
        }
    )


# ----------------------------------------------------------------------------- read
def list_logs(store: ArtifactStore) -> list[str]:
    """Sorted seq_ids of the complete logs in ``store`` (directories with a manifest)."""
    return [
        name
        for name in store.listdir(LOGS_DIR)
        if _SAFE_NAME.match(name) and read_marker(store, join_relpath(LOGS_DIR, name)) is not None
    ]


def read_scene_log(store: ArtifactStore, seq_id: str, load_images: bool = True) -> SceneLog:
    """Reconstruct the ``SceneLog`` written by ``write_scene_log``.

    Args:
        load_images: when False, ``CameraImage.image/depth/instance`` stay ``None`` (calibration and
            poses only; no EXR is read).

    Raises:
        FileNotFoundError: no complete log (missing manifest) for ``seq_id``.
        SchemaError, CorruptArtifactError: a table or image does not decode, or a file disagrees with the
            manifest (size, row count; ``storage.integrity``), naming the file.
    """
    rel = log_dir(seq_id)
    manifest = read_marker(store, rel)
    if manifest is None:
        raise FileNotFoundError(f"{store.uri(rel)}: no complete scene log (missing or unreadable _SUCCESS.json)")
    tables = {name: store.read_table(join_relpath(rel, f"{name}.parquet"), s) for name, s in LOG_TABLES.items()}
    ego = tables["ego_poses"].sort_by("frame_idx")
    log = SceneLog(
        seq_id=seq_id,
        source=str(manifest.get("source", "")),
        timestamps_us=ego.column("timestamp_us").to_numpy().astype(np.int64),
        ego_poses=arrow_to_vectors(ego.column("ego_to_world")).astype(np.float64).reshape(-1, 4, 4),
        images=_read_images(store, rel, tables["frames"], load_images),
        tracks=_read_tracks(tables["tracks"], tables["objects"]),
        objects=_read_objects(tables["objects"]),
        map_features=_read_map_features(tables["map_features"]),
        metadata={str(k): str(v) for k, v in manifest.get("metadata", {}).items()},
    )
    require_intact(store, rel, manifest, MARKER_NAME)  # after decoding: a file's own error names it more precisely
    return log.validate()


def read_image_rgb(store: ArtifactStore, seq_id: str, camera: str, frame_idx: int) -> np.ndarray | None:
    """``[H, W, 3]`` float32 pixels of one stored camera image (``None`` when the log has no pixels
    there), for callers that read a log with ``load_images=False`` and need a few frames only."""
    rel = join_relpath(log_dir(seq_id), _image_relpath(camera, frame_idx))
    return _rgb(read_exr(store, rel)) if store.exists(rel) else None


def _read_images(store: ArtifactStore, rel: str, frames: pa.Table, load_images: bool) -> tuple[CameraImage, ...]:
    names = ("frame_idx", "timestamp_us", "camera", "image_uri", "width", "height", "split")
    cols = {name: frames.column(name).to_pylist() for name in names}
    K = arrow_to_vectors(frames.column("K")).astype(np.float64).reshape(-1, 3, 3)
    c2w = arrow_to_vectors(frames.column("cam_to_world")).astype(np.float64).reshape(-1, 4, 4)
    images = []
    for i in range(frames.num_rows):
        uri = cols["image_uri"][i]
        channels = read_exr(store, join_relpath(rel, uri)) if load_images and uri else {}
        rgb = _rgb(channels)
        instance = channels["id"].astype(np.int32) if "id" in channels else None
        images.append(
            CameraImage(
                frame_idx=cols["frame_idx"][i],
                timestamp_us=cols["timestamp_us"][i],
                camera=cols["camera"][i],
                K=K[i],
                cam_to_world=c2w[i],
                width=cols["width"][i],
                height=cols["height"][i],
                image=rgb,
                depth=channels.get("Z"),
                instance=instance,
                split=cols["split"][i],
                valid_mask=channels[MASK_CHANNEL] > 0.5 if MASK_CHANNEL in channels else None,
            )
        )
    return tuple(images)


def _read_tracks(tracks: pa.Table, objects: pa.Table) -> tuple[Track, ...]:
    ids = np.asarray(tracks.column("object_id").to_pylist(), dtype=object)
    frame_idx = tracks.column("frame_idx").to_numpy().astype(np.int64)
    center = arrow_to_vectors(tracks.column("center")).astype(np.float64)
    size = arrow_to_vectors(tracks.column("size")).astype(np.float64)
    heading = tracks.column("heading").to_numpy().astype(np.float64)
    speed = tracks.column("speed").to_numpy().astype(np.float64)
    visible = np.asarray(tracks.column("visible").to_pylist(), dtype=bool)
    order = list(dict.fromkeys(ids.tolist()))
    seen = set(order)
    # objects whose track has no rows (empty tracks) come after, in objects order
    order += [oid for oid in objects.column("object_id").to_pylist() if oid not in seen]
    result = []
    for oid in order:
        rows = np.flatnonzero(ids == oid)
        rows = rows[np.argsort(frame_idx[rows], kind="stable")]
        result.append(
            Track(
                object_id=oid,
                frame_idx=frame_idx[rows],
                center=center[rows].reshape(-1, 3),
                size=size[rows].reshape(-1, 3),
                heading=heading[rows],
                speed=speed[rows],
                visible=visible[rows],
            )
        )
    return tuple(result)


def _read_objects(objects: pa.Table) -> tuple[ObjectInfo, ...]:
    rows = objects.to_pylist()
    return tuple(
        ObjectInfo(
            object_id=r["object_id"],
            category=r["category"],
            node_type=r["node_type"],
            instance_id=r["instance_id"],
            caption=r["caption"],
            attributes=dict(r["attributes"]),
        )
        for r in rows
    )


def _read_map_features(features: pa.Table) -> tuple[MapFeature, ...]:
    points = features.column("points").combine_chunks()
    offsets = points.offsets.to_numpy()
    values = arrow_to_vectors(points.values).astype(np.float64) if len(points) else np.zeros((0, 3))
    ids = features.column("feature_id").to_pylist()
    kinds = features.column("kind").to_pylist()
    return tuple(
        MapFeature(feature_id=fid, kind=kind, points=values[offsets[i] : offsets[i + 1]])
        for i, (fid, kind) in enumerate(zip(ids, kinds))
    )
