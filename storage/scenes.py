"""Persist reconstructed scene graphs under ``scenes/<seq_id>/<scene_hash>/`` and read them back.

Layout of one scene (written inside one ``staged_directory``, so it appears complete or not at all)::

    scenes/<seq_id>/<scene_hash>/gaussians.parquet    one row per Gaussian (canonical, node-local frame)
                                 nodes.parquet        one row per scene-graph node
                                 node_poses.parquet   one row per (node, frame): node -> world transform
                                 deform/<node_id>.parquet   non-rigid nodes: one row per frame, [N_h, 3] offsets
                                 metrics.parquet      one row per metric (stage "reconstruct")
                                 renders/<camera>/<frame_idx:06d>.exr   test-frame renders: R,G,B,A,Z,id
                                 _SUCCESS.json        manifest: content key, counts, bytes, metrics, provenance

``<scene_hash>`` is the content key of the stage's inputs (log, config, versions) computed by the
caller; the manifest's ``key`` equals it, so a directory is a *complete* scene exactly when its marker
names its own hash. ``node_poses.deform_uri`` is the deformation file relative to the scene directory
(``deform/<node_id>.parquet``) for non-rigid nodes and ``""`` for the others.

Node features: ``nodes.f_app/f_mot/f_loc`` are written as zeros of width ``feature_dim`` (default
``DEFAULT_NODE_FEATURE_DIM`` = 384, the text-embedding width of the E5 encoder used by language
alignment). The width is recorded in the file metadata, so a later stage may rewrite the table with
real features of any width; readers take the width from the file.

Node geometry: the nodes table also holds each node's ``scale`` and (background) ``center``, which
``SceneGraph.from_records`` needs.

Precision: every array is float32 (``storage.schemas``); float32 inputs round-trip bit-exactly (node
``scale``/``center``, Python floats, are rounded once to float32).
Renders go through EXR (float32, zip): bit-exact too; node ids are exact up to ``2**24``.
"""

from __future__ import annotations

import datetime
import logging
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import pyarrow as pa

from storage.errors import CorruptArtifactError
from storage.exr import read_exr, render_channels, write_exr
from storage.integrity import require_intact
from storage.markers import MARKER_NAME, is_done, mark_done, read_marker
from storage.schemas.base import arrow_to_vectors, schema_version, vectors_to_arrow
from storage.schemas.runs import METRICS_SCHEMA
from storage.schemas.scenes import DEFORMATIONS_SCHEMA, NODE_POSES_SCHEMA, gaussians_schema, nodes_schema
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

SCENES_DIR = "scenes"
RENDERS_DIR = "renders"
DEFORM_DIR = "deform"
MANIFEST_FORMAT = "simsplat.scene"
#: Version of this on-disk layout; part of every scene hash (see ``tasks.reconstruct``).
SCENE_FORMAT_VERSION = 1
#: Width of the placeholder node features (E5 text-embedding width).
DEFAULT_NODE_FEATURE_DIM = 384
#: Stage name in ``metrics.parquet``.
METRICS_STAGE = "reconstruct"
#: Units of the known reconstruction metrics; others get ``""``.
METRIC_UNITS: dict[str, str] = {
    "psnr_test": "dB",
    "psnr_test_dynamic": "dB",
    "psnr_train": "dB",
    "ssim_test": "",
    "ssim_test_dynamic": "",
    "iterations": "count",
    "wall_time_s": "s",
    "seconds_per_iteration": "s",
    "num_gaussians": "count",
    "num_nodes": "count",
}
GAUSSIAN_COLUMNS: tuple[str, ...] = ("node_id", "mean", "log_scale", "quat", "color", "opacity_logit")
NODE_KEYS: tuple[str, ...] = ("node_id", "node_type", "object_id", "category")
#: Optional node geometry: ``scale`` (default 1.0) and, for the background node only, ``center`` [3].
NODE_GEOMETRY_KEYS: tuple[str, ...] = ("scale", "center")
_HASH = re.compile(r"^[0-9a-f]{8,64}$")
_SAFE_NAME = re.compile(r"^[A-Za-z0-9_\-][A-Za-z0-9_.\-]*$")


class RenderLike(Protocol):
    """What ``write_scene`` reads of a test-frame render (``simsplat_core.scene.TestFrameRender``, frozen).

    Read-only properties, so frozen dataclasses satisfy it.
    """

    @property
    def frame_idx(self) -> int: ...
    @property
    def camera(self) -> str: ...
    @property
    def rgb(self) -> np.ndarray: ...  # [H, W, 3]
    @property
    def alpha(self) -> np.ndarray: ...  # [H, W] or [H, W, 1]
    @property
    def depth(self) -> np.ndarray: ...  # [H, W] or [H, W, 1]
    @property
    def node_id(self) -> np.ndarray: ...  # [H, W] int


def _check_name(kind: str, value: str) -> str:
    if not _SAFE_NAME.match(value or ""):
        raise ValueError(f"{kind} {value!r} is not safe as a directory name (letters, digits, '_', '-', '.')")
    return value


def _check_hash(scene_hash: str) -> str:
    if not _HASH.match(scene_hash or ""):
        raise ValueError(f"scene hash {scene_hash!r} must be 8-64 lowercase hex digits")
    return scene_hash


def scenes_dir(seq_id: str) -> str:
    """``scenes/<seq_id>``: every reconstruction of one sequence."""
    return join_relpath(SCENES_DIR, _check_name("seq_id", seq_id))


def scene_dir(seq_id: str, scene_hash: str) -> str:
    """``scenes/<seq_id>/<scene_hash>``: one reconstruction."""
    return join_relpath(scenes_dir(seq_id), _check_hash(scene_hash))


def scene_id_for(seq_id: str, scene_hash: str) -> str:
    """The ``scene_id`` written in the tables: ``<seq_id>/<first 16 hex digits of the hash>``."""
    return f"{seq_id}/{scene_hash[:16]}"


def render_relpath(camera: str, frame_idx: int) -> str:
    """Render path inside a scene directory: ``renders/<camera>/<frame_idx:06d>.exr``."""
    return f"{RENDERS_DIR}/{_check_name('camera', camera)}/{int(frame_idx):06d}.exr"


def deform_relpath(node_id: int) -> str:
    """Deformation file of a non-rigid node inside a scene directory: ``deform/<node_id>.parquet``."""
    return f"{DEFORM_DIR}/{int(node_id)}.parquet"


# ----------------------------------------------------------------------------- queries
def read_scene_manifest(store: ArtifactStore, seq_id: str, scene_hash: str) -> dict | None:
    """The manifest of a complete scene, or ``None`` when it is absent or incomplete."""
    rel = scene_dir(seq_id, scene_hash)
    marker = read_marker(store, rel)
    return marker if marker is not None and marker["key"] == scene_hash else None


def scene_exists(store: ArtifactStore, seq_id: str, scene_hash: str) -> bool:
    """Whether a complete scene with this hash is stored."""
    return is_done(store, scene_dir(seq_id, scene_hash), scene_hash)


def list_scenes(store: ArtifactStore, seq_id: str) -> list[str]:
    """Hashes of the complete scenes of ``seq_id``, oldest first (by the manifest's ``written_at``)."""
    found: list[tuple[str, str]] = []
    for name in store.listdir(scenes_dir(seq_id)):
        if _HASH.match(name):
            manifest = read_scene_manifest(store, seq_id, name)
            if manifest is not None:
                found.append((str(manifest.get("written_at", "")), name))
    return [name for _, name in sorted(found)]


def resolve_scene_hash(store: ArtifactStore, seq_id: str, scene_hash: str | None = None) -> str:
    """The full hash of a complete scene: the newest when ``scene_hash`` is ``None``, else the one it
    names (a unique prefix of at least 8 hex digits is enough).

    Raises:
        FileNotFoundError: no (matching) complete scene, naming the directory.
        ValueError: an ambiguous prefix.
    """
    where = store.uri(scenes_dir(seq_id))
    complete = list_scenes(store, seq_id)
    if scene_hash is None:
        if not complete:
            raise FileNotFoundError(f"{where}: no complete reconstructed scene (run `simsplat reconstruct`)")
        return complete[-1]
    _check_hash(scene_hash)
    matches = [h for h in complete if h.startswith(scene_hash)]
    if not matches:
        raise FileNotFoundError(
            f"{store.uri(join_relpath(scenes_dir(seq_id), scene_hash))}: no complete scene "
            f"(missing or incomplete _SUCCESS.json); complete scenes: {[h[:12] for h in complete]}"
        )
    if len(matches) > 1:
        raise ValueError(f"{where}: scene hash prefix {scene_hash!r} is ambiguous: {[h[:12] for h in matches]}")
    return matches[0]


# ----------------------------------------------------------------------------- write
@dataclass(frozen=True)
class WrittenScene:
    """Outcome of ``write_scene``.

    Attributes:
        relpath: ``scenes/<seq_id>/<scene_hash>``.
        scene_hash: the content key it is stored under.
        bytes: total size of the scene's tables, deformations and renders.
        skipped: True when a complete scene with this hash was already stored.
    """

    relpath: str
    scene_hash: str
    bytes: int
    skipped: bool


def metrics_to_json(metrics: Mapping[str, float]) -> dict[str, float | None]:
    """``name -> value`` with ``nan``/``inf`` as ``None`` (strict JSON for manifests and artifacts)."""
    return {k: (float(v) if np.isfinite(float(v)) else None) for k, v in metrics.items()}


def metrics_from_json(metrics: Mapping[str, float | None]) -> dict[str, float]:
    """Inverse of ``metrics_to_json`` (``None`` -> ``nan``)."""
    return {k: (float("nan") if v is None else float(v)) for k, v in metrics.items()}


def scene_bytes(manifest: Mapping[str, Any]) -> int:
    """Total bytes of a scene's files, from its manifest."""
    tables = manifest.get("tables", {})
    groups = ("deformations", "renders")
    return int(sum(t.get("bytes", 0) for t in tables.values())
               + sum(manifest.get(g, {}).get("bytes", 0) for g in groups))


def write_scene(
    store: ArtifactStore,
    seq_id: str,
    scene_hash: str,
    records: Any,
    metrics: Mapping[str, float],
    renders: Iterable[RenderLike] = (),
    *,
    run_id: str = "",
    feature_dim: int = DEFAULT_NODE_FEATURE_DIM,
    provenance: Mapping[str, Any] | None = None,
    overwrite: bool = False,
) -> WrittenScene:
    """Write one reconstructed scene atomically under ``scenes/<seq_id>/<scene_hash>/``.

    Args:
        records: a ``simsplat_core.scene.SceneRecords`` (numpy columns; see the module docstring).
        metrics: ``name -> value`` (stored with stage ``"reconstruct"`` and the units of ``METRIC_UNITS``).
        renders: test-frame renders, written as EXR (``R,G,B,A,Z,id``).
        run_id: the ``run_id`` column of ``metrics.parquet`` (default: the scene hash).
        feature_dim: width of the zero placeholder node features.
        provenance: JSON-serialisable facts (config, log key, versions) stored in the manifest.
        overwrite: rewrite even when a complete scene with this hash exists.

    Raises:
        ValueError: unsafe names, a malformed hash, or inconsistent records (``SceneRecords.validate``).
        SchemaError: a table does not match its schema (naming the file and the column).
    """
    rel = scene_dir(seq_id, scene_hash)
    if not overwrite and scene_exists(store, seq_id, scene_hash):
        logger.info("scene %s already complete, skipping write", store.uri(rel))
        return WrittenScene(rel, scene_hash, scene_bytes(read_marker(store, rel) or {}), True)

    records.validate()
    scene_id = str(records.scene_id)
    deformations = _deformations(records)
    tables = {
        "gaussians": gaussians_table(scene_id, records.gaussians),
        "nodes": nodes_table(scene_id, records.nodes, feature_dim),
        "node_poses": _node_poses_table(scene_id, records.node_poses, set(deformations)),
        "metrics": _metrics_table(run_id or scene_hash, seq_id, metrics),
    }
    renders = list(renders)
    with store.staged_directory(rel) as tmp:
        table_stats = {}
        for name, (table, schema) in tables.items():
            path = join_relpath(tmp, f"{name}.parquet")
            store.write_table(path, table, schema)
            table_stats[name] = {"rows": table.num_rows, "bytes": store.size(path),
                                 "schema_version": schema_version(schema)}
        deform_bytes = 0
        for node_id, (frames, offsets) in deformations.items():
            path = join_relpath(tmp, deform_relpath(node_id))
            store.write_table(path, deformation_table(scene_id, node_id, frames, offsets), DEFORMATIONS_SCHEMA)
            deform_bytes += store.size(path)
        render_bytes = 0
        for r in renders:
            path = join_relpath(tmp, render_relpath(r.camera, r.frame_idx))
            write_exr(store, path, render_channels(rgb=r.rgb, alpha=r.alpha, depth=r.depth, node_id=r.node_id))
            render_bytes += store.size(path)
        manifest = {
            "format": MANIFEST_FORMAT,
            "format_version": SCENE_FORMAT_VERSION,
            "seq_id": seq_id,
            "scene_id": scene_id,
            "frame_indices": [int(f) for f in np.asarray(records.frame_indices).reshape(-1)],
            "metadata": {str(k): str(v) for k, v in records.metadata.items()},
            "node_feature_dim": feature_dim,
            "tables": table_stats,
            "deformations": {"count": len(deformations), "bytes": deform_bytes, "nodes": sorted(deformations)},
            "renders": {
                "count": len(renders),
                "bytes": render_bytes,
                "files": sorted(render_relpath(r.camera, r.frame_idx) for r in renders),
            },
            "metrics": metrics_to_json(metrics),
            "written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds"),
            "provenance": dict(provenance or {}),
        }
        mark_done(store, tmp, scene_hash, manifest)
    logger.info(
        "wrote scene %s (%d Gaussians, %d nodes, %d renders)",
        store.uri(rel), tables["gaussians"][0].num_rows, tables["nodes"][0].num_rows, len(renders),
    )
    return WrittenScene(rel, scene_hash, scene_bytes(manifest), False)


def _strings(value: str, n: int) -> pa.Array:
    return pa.array([value] * n, pa.string())


def _column(columns: Mapping[str, Any], name: str, dtype: type, where: str) -> np.ndarray:
    if name not in columns:
        raise ValueError(f"{where}: column {name!r} is missing (have {sorted(columns)})")
    return np.asarray(columns[name], dtype=dtype)


def _equal_lengths(where: str, arrays: Mapping[str, np.ndarray]) -> int:
    lengths = {name: len(a) for name, a in arrays.items()}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"{where}: columns differ in length: {lengths}")
    return next(iter(lengths.values()), 0)


def gaussians_table(scene_id: str, columns: Mapping[str, Any]) -> tuple[pa.Table, pa.Schema]:
    where = "gaussians"
    arrays = {name: _column(columns, name, np.float32, where) for name in GAUSSIAN_COLUMNS if name != "node_id"}
    arrays["node_id"] = _column(columns, "node_id", np.int32, where)
    if "feature" in columns:
        arrays["feature"] = np.asarray(columns["feature"], dtype=np.float32)
    n = _equal_lengths(where, arrays)
    color_dim = arrays["color"].reshape(n, -1).shape[1] if n else int(np.shape(arrays["color"])[-1])
    feature_dim = arrays["feature"].reshape(n, -1).shape[1] if "feature" in arrays and n else 0
    data: dict[str, pa.Array] = {"scene_id": _strings(scene_id, n), "node_id": pa.array(arrays["node_id"], pa.int32())}
    widths = {"mean": 3, "log_scale": 3, "quat": 4, "color": color_dim}
    for name, width in widths.items():
        data[name] = vectors_to_arrow(arrays[name], width)
    data["opacity_logit"] = pa.array(arrays["opacity_logit"].reshape(n), pa.float32())
    if feature_dim:
        data["feature"] = vectors_to_arrow(arrays["feature"], feature_dim)
    return pa.table(data), gaussians_schema(feature_dim=feature_dim, color_dim=color_dim)


def nodes_table(scene_id: str, nodes: Sequence[Mapping[str, Any]], dim: int,
                features: Mapping[str, np.ndarray] | None = None) -> tuple[pa.Table, pa.Schema]:
    """The ``nodes`` table of ``nodes`` (node dicts as ``SceneGraph.to_records`` makes them); ``features``
    maps ``f_app``/``f_mot``/``f_loc`` to ``[len(nodes), dim]`` values (default zeros)."""
    for i, node in enumerate(nodes):
        missing = [k for k in NODE_KEYS if k not in node]
        unknown = [k for k in node if k not in NODE_KEYS + NODE_GEOMETRY_KEYS]
        if missing or unknown:
            raise ValueError(f"nodes[{i}]: missing key(s) {missing}, unknown key(s) {unknown} "
                             f"(the nodes table holds {list(NODE_KEYS + NODE_GEOMETRY_KEYS)})")
    n = len(nodes)
    zeros = vectors_to_arrow(np.zeros((n, dim), np.float32), dim)
    centers = np.array([np.asarray(nd.get("center", (0.0, 0.0, 0.0)), np.float32).reshape(3)
                        for nd in nodes]).reshape(n, 3)
    given = features or {}
    table = pa.table(
        {
            "scene_id": _strings(scene_id, n),
            "node_id": pa.array([int(nd["node_id"]) for nd in nodes], pa.int32()),
            "node_type": pa.array([str(nd["node_type"]) for nd in nodes], pa.string()),
            "object_id": pa.array([str(nd["object_id"]) for nd in nodes], pa.string()),
            "category": pa.array([str(nd["category"]) for nd in nodes], pa.string()),
            "scale": pa.array([float(nd.get("scale", 1.0)) for nd in nodes], pa.float32()),
            "center": vectors_to_arrow(centers, 3),
            **{name: zeros if name not in given else vectors_to_arrow(
                np.asarray(given[name], np.float32).reshape(n, dim), dim) for name in ("f_app", "f_mot", "f_loc")},
        }
    )
    return table, nodes_schema(dim)


def _node_poses_table(scene_id: str, poses: Mapping[str, Any], deformed: set[int]) -> tuple[pa.Table, pa.Schema]:
    where = "node_poses"
    arrays = {
        "node_id": _column(poses, "node_id", np.int32, where),
        "frame_idx": _column(poses, "frame_idx", np.int64, where),
        "transform": _column(poses, "transform", np.float32, where),
    }
    m = _equal_lengths(where, arrays)
    uris = [deform_relpath(int(nid)) if int(nid) in deformed else "" for nid in arrays["node_id"]]
    table = pa.table(
        {
            "scene_id": _strings(scene_id, m),
            "node_id": pa.array(arrays["node_id"], pa.int32()),
            "frame_idx": pa.array(arrays["frame_idx"], pa.int64()),
            "transform": vectors_to_arrow(arrays["transform"], 16),
            "deform_uri": pa.array(uris, pa.string()),
        }
    )
    return table, NODE_POSES_SCHEMA


def _metrics_table(run_id: str, seq_id: str, metrics: Mapping[str, float]) -> tuple[pa.Table, pa.Schema]:
    names = list(metrics)
    table = pa.table(
        {
            "run_id": _strings(run_id, len(names)),
            "seq_id": _strings(seq_id, len(names)),
            "stage": _strings(METRICS_STAGE, len(names)),
            "name": pa.array(names, pa.string()),
            "value": pa.array([float(metrics[k]) for k in names], pa.float64()),
            "unit": pa.array([METRIC_UNITS.get(k, "") for k in names], pa.string()),
        }
    )
    return table, METRICS_SCHEMA


def _deformations(records: Any) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """``node_id -> (frame_idx [T] int64, offsets [T, N_h, 3] float32)`` from the records."""
    result: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for node_id, offsets in records.deformations.items():
        offsets = np.asarray(offsets, dtype=np.float32)
        if node_id not in records.deformation_frames:
            raise ValueError(f"deformations[{node_id}]: no deformation_frames[{node_id}]")
        frames = np.asarray(records.deformation_frames[node_id], dtype=np.int64).reshape(-1)
        if offsets.ndim != 3 or offsets.shape[2] != 3 or offsets.shape[0] != len(frames):
            raise ValueError(
                f"deformations[{node_id}]: expected [T={len(frames)}, N_h, 3] offsets, got {offsets.shape}"
            )
        result[int(node_id)] = (frames, offsets)
    return result


def deformation_table(scene_id: str, node_id: int, frames: np.ndarray, offsets: np.ndarray) -> pa.Table:
    """The ``deformations`` table of one non-rigid node: ``frames [T]``, ``offsets [T, N_h, 3]``."""
    t, n_h, _ = offsets.shape
    values = vectors_to_arrow(offsets.reshape(t * n_h, 3), 3)
    row_offsets = pa.array(np.arange(t + 1, dtype=np.int32) * n_h)
    return pa.table(
        {
            "scene_id": _strings(scene_id, t),
            "node_id": pa.array(np.full(t, node_id, np.int32)),
            "frame_idx": pa.array(frames, pa.int64()),
            "offsets": pa.ListArray.from_arrays(row_offsets, values),
        }
    )


# ----------------------------------------------------------------------------- read
@dataclass(frozen=True)
class LoadedScene:
    """A stored scene read back by ``read_scene``.

    Attributes:
        seq_id, scene_hash: which scene.
        relpath: ``scenes/<seq_id>/<scene_hash>``.
        records: ``simsplat_core.scene.SceneRecords`` (feed to ``SceneGraph.from_records``).
        metrics: ``name -> value`` from ``metrics.parquet``.
        manifest: the ``_SUCCESS.json`` content.
    """

    seq_id: str
    scene_hash: str
    relpath: str
    records: Any
    metrics: dict[str, float] = field(default_factory=dict)
    manifest: dict[str, Any] = field(default_factory=dict)


def read_scene(store: ArtifactStore, seq_id: str, scene_hash: str | None = None) -> LoadedScene:
    """Read a complete scene back (the newest one of ``seq_id`` when ``scene_hash`` is omitted).

    ``scene_hash`` may be a unique prefix (>= 8 hex digits) of a stored hash.

    Raises:
        FileNotFoundError: no complete scene (or a file of it is missing), naming the path.
        SchemaError, CorruptArtifactError: a table does not decode or validate, or a file disagrees with the
            manifest (size, row count; ``storage.integrity``), naming file and column.
    """
    full_hash = resolve_scene_hash(store, seq_id, scene_hash)
    rel = scene_dir(seq_id, full_hash)
    manifest = read_scene_manifest(store, seq_id, full_hash) or {}
    gaussians = store.read_table(join_relpath(rel, "gaussians.parquet"), "gaussians")
    nodes = store.read_table(join_relpath(rel, "nodes.parquet"), "nodes")
    poses = store.read_table(join_relpath(rel, "node_poses.parquet"), NODE_POSES_SCHEMA)
    metrics = store.read_table(join_relpath(rel, "metrics.parquet"), METRICS_SCHEMA)
    listed = manifest.get("deformations", {}).get("nodes", [])
    deformations, deformation_frames = _read_deformations(store, rel, poses, listed)
    require_intact(store, rel, manifest, MARKER_NAME)  # after decoding: a file's own error names it more precisely
    records = _records_class()(
        scene_id=str(manifest.get("scene_id", "")),
        frame_indices=np.asarray(manifest.get("frame_indices", []), dtype=np.int64),
        gaussians=gaussian_columns(gaussians),
        nodes=_node_dicts(nodes),
        node_poses={
            "node_id": poses.column("node_id").to_numpy().astype(np.int32),
            "frame_idx": poses.column("frame_idx").to_numpy().astype(np.int64),
            "transform": arrow_to_vectors(poses.column("transform")),
        },
        deformations=deformations,
        deformation_frames=deformation_frames,
        metadata={str(k): str(v) for k, v in manifest.get("metadata", {}).items()},
    )
    values = dict(zip(metrics.column("name").to_pylist(), metrics.column("value").to_pylist()))
    logger.debug("read scene %s", store.uri(rel))
    return LoadedScene(seq_id, full_hash, rel, records, {k: float(v) for k, v in values.items()}, manifest)


def _records_class() -> type:
    """``simsplat_core.scene.SceneRecords``, imported on first use (the scene package imports torch)."""
    from simsplat_core.scene import SceneRecords  # noqa: PLC0415  # slow (torch), see docstring

    return SceneRecords


def _node_dicts(nodes: pa.Table) -> list[dict[str, Any]]:
    """Node dicts as ``SceneGraph.to_records`` makes them (``center`` only on the background node)."""
    result = []
    for row in nodes.select([*NODE_KEYS, *NODE_GEOMETRY_KEYS]).to_pylist():
        node = {k: row[k] for k in NODE_KEYS}
        node["scale"] = float(row["scale"])
        if row["node_type"] == "background":
            node["center"] = [float(c) for c in row["center"]]
        result.append(node)
    return result


def gaussian_columns(table: pa.Table) -> dict[str, np.ndarray]:
    columns = {"node_id": table.column("node_id").to_numpy().astype(np.int32)}
    for name in ("mean", "log_scale", "quat", "color"):
        columns[name] = arrow_to_vectors(table.column(name))
    columns["opacity_logit"] = table.column("opacity_logit").to_numpy().astype(np.float32)
    if "feature" in table.schema.names:
        columns["feature"] = arrow_to_vectors(table.column("feature"))
    return columns


def _read_deformations(
    store: ArtifactStore, rel: str, poses: pa.Table, listed: Sequence[int]
) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
    """Per-node offsets ``[T, N_h, 3]`` and their frame indices ``[T]``.

    Read from the files ``node_poses.deform_uri`` names, plus those of the nodes ``listed`` in the
    manifest (a non-rigid node without pose rows has no ``deform_uri``).
    """
    uris: dict[int, str] = {}
    for node_id, uri in zip(poses.column("node_id").to_pylist(), poses.column("deform_uri").to_pylist()):
        if uri:
            uris.setdefault(int(node_id), uri)
    for node_id in listed:
        uris.setdefault(int(node_id), deform_relpath(node_id))
    offsets: dict[int, np.ndarray] = {}
    frames: dict[int, np.ndarray] = {}
    for node_id, uri in uris.items():
        frames[node_id], offsets[node_id] = read_deformation_table(store, join_relpath(rel, uri))
    return offsets, frames


def read_deformation_table(store: ArtifactStore, path: str) -> tuple[np.ndarray, np.ndarray]:
    """``(frame_idx [T] int64, offsets [T, N_h, 3] float32)`` of one ``deformations`` file, by frame.

    Raises:
        CorruptArtifactError: rows of different lengths in column ``offsets`` (naming the file).
    """
    table = store.read_table(path, DEFORMATIONS_SCHEMA).sort_by("frame_idx")
    column = table.column("offsets").combine_chunks()
    counts = set(np.diff(column.offsets.to_numpy()).tolist())
    if len(counts) > 1:
        raise CorruptArtifactError(f"{store.uri(path)}: column 'offsets' has rows of different lengths "
                                   f"{sorted(counts)}")
    n_h = counts.pop() if counts else 0
    values = arrow_to_vectors(column.values) if len(column) else np.zeros((0, 3), np.float32)
    return table.column("frame_idx").to_numpy().astype(np.int64), values.reshape(len(column), n_h, 3)


def read_scene_render(store: ArtifactStore, seq_id: str, scene_hash: str, camera: str,
                      frame_idx: int) -> dict[str, np.ndarray]:
    """The EXR channels (``R,G,B,A,Z,id``) of one stored test-frame render."""
    return read_exr(store, join_relpath(scene_dir(seq_id, scene_hash), render_relpath(camera, frame_idx)))
