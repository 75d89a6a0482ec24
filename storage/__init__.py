"""Storage layer: everything that reads or writes the artifact store, with atomic writes throughout.

* ``store``: ``ArtifactStore`` over ``pyarrow.fs`` (local paths or object-store URIs), atomic puts.
* ``uris``: object-store URIs (a path joined before the query options; credentials refused: environment only).
* ``remote_folder``: local mirrors and temporary copies of object-store folders (landing locations in buckets).
* ``schemas``: every Parquet table's ``pyarrow.schema`` with its version, validated on read.
* ``parquet_io``, ``exr``, ``pictures``: table, EXR (OpenImageIO, zip) and PNG / MP4 I/O.
* ``keys``, ``markers``: content keys of stage inputs/configs and the ``_SUCCESS.json`` manifests that
  mark finished work (a re-run skips it); ``integrity``: the file sizes and checksums a manifest records,
  checked before reuse (a corrupt artifact is reported and recomputed).
* ``logs``, ``scenes``: scene logs (``logs/<seq_id>``) and reconstructed scenes (``scenes/<seq_id>/<hash>``).
* ``alignment``, ``language_scenes``: the motion aligner models and language scenes (``alignment/``).
* ``runs``: run directories and evaluation tables (``runs/<run_id>/tables``).
* ``assets``: asset banks for scene editing (``assets/<bank_hash>``).
* ``inventory``: whether a sequence has a complete log / reconstructed scene / language scene (and the store an
  asset bank), else one ``MissingInputError`` naming the command that makes it; imported on use.
* ``edits``: language edits (``edits/<run_id>/<seq_id>/<edit_id>``, the run's ``edits`` table); imported on
  use (it loads the editing core), not re-exported here.

Imports ``simsplat_core`` (types, scene records, language scenes); never prefect or ray.
``simsplat_core`` never imports this.
"""

from storage.assets import list_asset_banks, read_asset_bank, write_asset_bank
from storage.errors import CorruptArtifactError, SchemaError, StorageError, UnsafePathError
from storage.exr import (
    BASE_CHANNELS,
    MAX_EXACT_ID,
    canonical_order,
    feature_channel,
    read_exr,
    read_exr_header,
    render_channels,
    write_exr,
)
from storage.keys import canonical, config_settings, content_key
from storage.logs import (
    WrittenLog,
    image_uri,
    list_logs,
    log_dir,
    manifest_bytes,
    read_log_manifest,
    read_scene_log,
    require_log_manifest,
    scene_log_key,
    write_scene_log,
)
from storage.markers import MARKER_NAME, intact_marker, is_done, mark_done, read_marker
from storage.scenes import (
    LoadedScene,
    WrittenScene,
    list_scenes,
    read_scene,
    read_scene_manifest,
    read_scene_render,
    resolve_scene_hash,
    scene_dir,
    scene_exists,
    write_scene,
)
from storage.schemas.base import arrow_to_vectors, schema_name, schema_version, vec, vectors_to_arrow
from storage.schemas.edits import ASSETS_SCHEMA, EDITS_SCHEMA, TRAJECTORIES_SCHEMA
from storage.schemas.logs import EGO_POSES_SCHEMA, FRAMES_SCHEMA, MAP_FEATURES_SCHEMA, OBJECTS_SCHEMA, TRACKS_SCHEMA
from storage.schemas.registry import TABLES, StoredTable, schema_from_metadata
from storage.schemas.runs import METRICS_SCHEMA
from storage.schemas.scenes import DEFORMATIONS_SCHEMA, NODE_POSES_SCHEMA, gaussians_schema, nodes_schema
from storage.schemas.validation import json_schema, validate_table
from storage.store import ArtifactStore, join_relpath, normalize_relpath

__all__ = [
    "list_asset_banks",
    "read_asset_bank",
    "write_asset_bank",
    "ASSETS_SCHEMA",
    "BASE_CHANNELS",
    "DEFORMATIONS_SCHEMA",
    "EDITS_SCHEMA",
    "EGO_POSES_SCHEMA",
    "FRAMES_SCHEMA",
    "MAP_FEATURES_SCHEMA",
    "MARKER_NAME",
    "MAX_EXACT_ID",
    "METRICS_SCHEMA",
    "NODE_POSES_SCHEMA",
    "OBJECTS_SCHEMA",
    "TABLES",
    "TRACKS_SCHEMA",
    "TRAJECTORIES_SCHEMA",
    "ArtifactStore",
    "CorruptArtifactError",
    "SchemaError",
    "StorageError",
    "StoredTable",
    "UnsafePathError",
    "arrow_to_vectors",
    "canonical",
    "canonical_order",
    "config_settings",
    "content_key",
    "feature_channel",
    "gaussians_schema",
    "image_uri",
    "intact_marker",
    "is_done",
    "join_relpath",
    "json_schema",
    "list_logs",
    "log_dir",
    "mark_done",
    "nodes_schema",
    "normalize_relpath",
    "read_exr",
    "read_exr_header",
    "read_marker",
    "read_scene_log",
    "require_log_manifest",
    "render_channels",
    "scene_log_key",
    "schema_from_metadata",
    "schema_name",
    "schema_version",
    "validate_table",
    "vec",
    "vectors_to_arrow",
    "write_exr",
    "write_scene_log",
    "WrittenLog",
    "LoadedScene",
    "WrittenScene",
    "list_scenes",
    "read_scene",
    "read_scene_manifest",
    "read_scene_render",
    "resolve_scene_hash",
    "scene_dir",
    "scene_exists",
    "write_scene",
    "manifest_bytes",
    "read_log_manifest",
]
