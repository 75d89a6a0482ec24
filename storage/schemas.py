"""The pyarrow schema of every persisted table, defined once (``DESIGN.md``, "Data contracts").

Each schema carries file metadata ``schema_name`` and ``schema_version`` (and, for tables with a
variable array width, the width: ``feature_dim``/``color_dim`` for ``gaussians``, ``dim`` for
``nodes``). ``validate_table`` checks a table against a schema and raises ``SchemaError`` naming the
file and every offending column.

Type decisions:

* Fixed-width arrays are ``FixedSizeList<float32>`` (``K[9]`` and 4x4 transforms row-major in
  ``[16]``). Transforms are float32 too: the world frame is the first ego pose, so translations stay
  within a log's extent (<= a few km), where float32 resolves better than 0.5 mm; rotation entries
  keep ~1e-7 relative precision. Scalars that are measurements (``heading``, ``speed``, ``x``, ``y``)
  are float32; metric ``value`` is float64 (aggregates must not lose digits).
* Time is int64 microseconds; frame indices are int64; scene-graph ``node_id`` is int32 (it is
  also written to the EXR ``id`` channel as float32, exact up to 2**24).
* ``objects.attributes`` is ``map<string, string>`` (native, queryable, keeps insertion order).
* ``map_features.points`` is ``list<FixedSizeList<float32, 3>>`` (one variable-length polyline).
* ``deformations.offsets`` is ``list<FixedSizeList<float32, 3>>`` too: the ``[N_h, 3]`` offsets of one
  non-rigid node's Gaussians at one frame (one file per node, ``node_poses.deform_uri`` points at it).
  The asset bank stores a deformable asset's offsets the same way (``assets.deform_uri``).
* Strings are never null: "absent" is the empty string (``image_uri``, ``deform_uri``,
  ``failure_reason``, ``caption``). Every column is non-nullable, except columns added to a table in a later
  version (e.g. the ``edits`` table's mining columns): they are nullable, and a file of an older version that
  lacks them is read with them all null.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from storage.errors import SchemaError

SCHEMA_NAME_KEY = "schema_name"
SCHEMA_VERSION_KEY = "schema_version"


def vec(width: int) -> pa.DataType:
    """``FixedSizeList<float32>[width]``."""
    return pa.list_(pa.float32(), width)


def _schema(name: str, version: int, fields: list[tuple[str, pa.DataType]], *, nullable: tuple[str, ...] = (),
            **dims: int) -> pa.Schema:
    metadata = {SCHEMA_NAME_KEY: name, SCHEMA_VERSION_KEY: str(version)}
    metadata.update({key: str(value) for key, value in dims.items()})
    return pa.schema([pa.field(n, t, nullable=n in nullable) for n, t in fields], metadata=metadata)


# ----------------------------------------------------------------------------- log tables
FRAMES_SCHEMA = _schema(
    "frames",
    1,
    [
        ("seq_id", pa.string()),
        ("frame_idx", pa.int64()),
        ("timestamp_us", pa.int64()),
        ("camera", pa.string()),
        ("image_uri", pa.string()),  # EXR path relative to the log directory; "" when no pixels
        ("K", vec(9)),  # row-major 3x3 intrinsics
        ("cam_to_world", vec(16)),  # row-major 4x4, OpenCV camera -> world
        ("width", pa.int32()),
        ("height", pa.int32()),
        ("split", pa.string()),  # "train" | "test"
    ],
)

EGO_POSES_SCHEMA = _schema(
    "ego_poses",
    1,
    [
        ("seq_id", pa.string()),
        ("frame_idx", pa.int64()),
        ("timestamp_us", pa.int64()),
        ("ego_to_world", vec(16)),  # row-major 4x4
    ],
)

TRACKS_SCHEMA = _schema(
    "tracks",
    1,
    [
        ("seq_id", pa.string()),
        ("object_id", pa.string()),
        ("frame_idx", pa.int64()),
        ("category", pa.string()),
        ("center", vec(3)),
        ("size", vec(3)),  # length, width, height
        ("heading", pa.float32()),
        ("speed", pa.float32()),
        ("visible", pa.bool_()),
    ],
)

OBJECTS_SCHEMA = _schema(
    "objects",
    1,
    [
        ("seq_id", pa.string()),
        ("object_id", pa.string()),
        ("category", pa.string()),
        ("node_type", pa.string()),  # "rigid" | "nonrigid" | "static"
        ("instance_id", pa.int32()),
        ("caption", pa.string()),
        ("attributes", pa.map_(pa.string(), pa.string())),
    ],
)

MAP_FEATURES_SCHEMA = _schema(
    "map_features",
    1,
    [
        ("seq_id", pa.string()),
        ("feature_id", pa.string()),
        ("kind", pa.string()),
        ("points", pa.list_(vec(3))),  # [P, 3] world coordinates
    ],
)


# ----------------------------------------------------------------------------- scene tables
def gaussians_schema(feature_dim: int, color_dim: int = 3) -> pa.Schema:
    """One row per Gaussian; ``color[color_dim]`` (3 for RGB, 3*(deg+1)**2 for SH), ``feature[feature_dim]``.

    ``feature_dim == 0`` means the scene has no language features: the ``feature`` column is omitted.
    """
    if feature_dim < 0 or color_dim <= 0:
        raise ValueError(f"gaussians_schema: need feature_dim >= 0 and color_dim > 0, got {feature_dim}, {color_dim}")
    fields = [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("mean", vec(3)),
        ("log_scale", vec(3)),
        ("quat", vec(4)),  # w, x, y, z
        ("color", vec(color_dim)),
        ("opacity_logit", pa.float32()),
    ]
    if feature_dim:
        fields.append(("feature", vec(feature_dim)))
    return _schema("gaussians", 1, fields, feature_dim=feature_dim, color_dim=color_dim)


def nodes_schema(dim: int) -> pa.Schema:
    """One row per scene-graph node; language features ``f_app``/``f_mot``/``f_loc`` of width ``dim``."""
    if dim <= 0:
        raise ValueError(f"nodes_schema: need dim > 0, got {dim}")
    return _schema(
        "nodes",
        1,
        [
            ("scene_id", pa.string()),
            ("node_id", pa.int32()),
            ("node_type", pa.string()),  # "background" | "rigid" | "nonrigid" | "static"
            ("object_id", pa.string()),  # "" for the background node
            ("category", pa.string()),
            ("scale", pa.float32()),  # characteristic size in metres (scene radius, box half-diagonal)
            ("center", vec(3)),  # background: scene centre (world); objects: zeros
            ("f_app", vec(dim)),
            ("f_mot", vec(dim)),
            ("f_loc", vec(dim)),
        ],
        dim=dim,
    )


NODE_LANGUAGE_SCHEMA = _schema(
    "node_language",
    1,
    [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("object_id", pa.string()),
        ("category", pa.string()),
        ("kind", pa.string()),  # motion codebook: "vehicle" | "pedestrian" | "" (static)
        ("has_appearance", pa.bool_()),  # nodes.f_app is real (the log had pixels of the object)
        ("has_motion", pa.bool_()),  # nodes.f_mot / f_loc are real (a moving agent with an aligner)
        ("caption", pa.string()),  # the captioner's description ("" without pixels)
        ("caption_json", pa.string()),  # AppearanceCaption fields as JSON ("" without pixels)
        ("motion_json", pa.string()),  # motion/location probabilities and auto-labels as JSON ("" if none)
    ],
)

NODE_POSES_SCHEMA = _schema(
    "node_poses",
    1,
    [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("frame_idx", pa.int64()),
        ("transform", vec(16)),  # row-major 4x4 node -> world
        ("deform_uri", pa.string()),  # non-rigid deformation artifact; "" for rigid nodes
    ],
)

DEFORMATIONS_SCHEMA = _schema(
    "deformations",
    1,
    [
        ("scene_id", pa.string()),
        ("node_id", pa.int32()),
        ("frame_idx", pa.int64()),
        ("offsets", pa.list_(vec(3))),  # [N_h, 3] per-Gaussian offsets of a non-rigid node at this frame
    ],
)

# ----------------------------------------------------------------------------- asset bank
ASSETS_SCHEMA = _schema(
    "assets",
    1,
    [
        ("bank_hash", pa.string()),
        ("asset_id", pa.string()),
        ("category", pa.string()),  # "vehicle" | "pedestrian" | "static"
        ("subtype", pa.string()),
        ("caption", pa.string()),
        ("color", pa.string()),
        ("size", vec(3)),  # box length, width, height (metres)
        ("source_seq", pa.string()),  # "" for procedural assets
        ("source_object", pa.string()),  # "" for procedural assets
        ("num_gaussians", pa.int64()),
        ("gaussians_uri", pa.string()),  # gaussians/<asset_id>.parquet, relative to the bank directory
        ("deform_uri", pa.string()),  # deform/<asset_id>.parquet for deformable assets, else ""
        ("deform_frames", pa.list_(pa.int64())),  # [T_h] source frames of the offsets (empty when rigid)
        ("deform_arc_length", pa.list_(pa.float32())),  # [T_h] metres walked up to each (empty when rigid)
        ("attributes", pa.map_(pa.string(), pa.string())),
    ],
)

# ----------------------------------------------------------------------------- run tables
#: Mining columns of the ``edits`` table (version 2; null in rows of ``simsplat edit`` and in version-1 files).
EDITS_MINING_COLUMNS: tuple[str, ...] = (
    "mining_status", "scenario", "source", "category", "follows_prompt", "plausibility", "adjustment", "export",
    "client", "seconds_propose", "seconds_command", "seconds_edit", "seconds_render", "seconds_judge",
)

EDITS_SCHEMA = _schema(
    "edits",
    2,  # 2: mining columns (nullable)
    [
        ("run_id", pa.string()),
        ("seq_id", pa.string()),
        ("edit_id", pa.string()),
        ("attempt", pa.int32()),
        ("prompt", pa.string()),
        ("command_json", pa.string()),
        ("status", pa.string()),
        ("failure_reason", pa.string()),  # "" when the attempt succeeded
        ("mining_status", pa.string()),  # "accepted" | "rejected" | "refused" | "failed" (mining.attempts)
        ("scenario", pa.int32()),  # index of the mined proposal in its sequence
        ("source", pa.string()),  # "seed" | "client"
        ("category", pa.string()),  # one of the six edit categories ("" when unknown)
        ("follows_prompt", pa.bool_()),  # the judge's answers (null when not judged)
        ("plausibility", pa.int32()),
        ("adjustment", pa.string()),  # what changed from the previous attempt
        ("export", pa.bool_()),  # an accepted scenario marked for export (false for a plain `simsplat edit`)
        ("client", pa.string()),  # the VLM client's name
        ("seconds_propose", pa.float64()),
        ("seconds_command", pa.float64()),
        ("seconds_edit", pa.float64()),
        ("seconds_render", pa.float64()),
        ("seconds_judge", pa.float64()),
    ],
    nullable=EDITS_MINING_COLUMNS,
)

TRAJECTORIES_SCHEMA = _schema(
    "trajectories",
    2,  # 2: category column, source "inserted"
    [
        ("edit_id", pa.string()),
        ("object_id", pa.string()),  # the log's id for existing agents ("ego" for the ego), a new one when inserted
        ("category", pa.string()),
        ("step", pa.int32()),  # the log's frame index
        ("x", pa.float32()),
        ("y", pa.float32()),
        ("heading", pa.float32()),
        ("speed", pa.float32()),  # signed, m/s (negative when reversing)
        ("source", pa.string()),  # "log" | "edited" | "inserted" | "refined"
    ],
)

EDIT_POSE_TRACKS_SCHEMA = _schema(
    "edit_pose_tracks",
    1,
    [
        ("node_id", pa.int32()),  # the node the track belongs to (added or re-tracked)
        ("t", pa.float64()),  # fractional frame index of the sample (may run past the log's frames)
        ("transform", vec(16)),  # row-major 4x4 node -> world
        ("present", pa.bool_()),
        ("arc_length", pa.float64()),  # metres along the new path (NaN: none; retimes a pedestrian's gait)
    ],
)

METRICS_SCHEMA = _schema(
    "metrics",
    1,
    [
        ("run_id", pa.string()),
        ("seq_id", pa.string()),
        ("stage", pa.string()),
        ("name", pa.string()),
        ("value", pa.float64()),
        ("unit", pa.string()),
    ],
)


# ----------------------------------------------------------------------------- registry
@dataclass(frozen=True)
class TableSpec:
    """How to build the schema of one table.

    Attributes:
        name: the ``schema_name``.
        build: keyword dims -> schema (dims are the integer metadata keys in ``dims``).
        dims: names of the integer dimensions stored in the file metadata.
        min_version: oldest ``schema_version`` this code still reads.
    """

    name: str
    build: Callable[..., pa.Schema]
    dims: tuple[str, ...] = ()
    min_version: int = 1

    @property
    def version(self) -> int:
        return schema_version(self.build(**{d: 1 for d in self.dims}))


def _fixed(schema: pa.Schema) -> Callable[[], pa.Schema]:
    return lambda: schema


TABLES: dict[str, TableSpec] = {
    spec.name: spec
    for spec in (
        TableSpec("frames", _fixed(FRAMES_SCHEMA)),
        TableSpec("ego_poses", _fixed(EGO_POSES_SCHEMA)),
        TableSpec("tracks", _fixed(TRACKS_SCHEMA)),
        TableSpec("objects", _fixed(OBJECTS_SCHEMA)),
        TableSpec("map_features", _fixed(MAP_FEATURES_SCHEMA)),
        TableSpec("gaussians", gaussians_schema, dims=("feature_dim", "color_dim")),
        TableSpec("nodes", nodes_schema, dims=("dim",)),
        TableSpec("node_poses", _fixed(NODE_POSES_SCHEMA)),
        TableSpec("node_language", _fixed(NODE_LANGUAGE_SCHEMA)),
        TableSpec("deformations", _fixed(DEFORMATIONS_SCHEMA)),
        TableSpec("assets", _fixed(ASSETS_SCHEMA)),
        TableSpec("edits", _fixed(EDITS_SCHEMA)),
        TableSpec("trajectories", _fixed(TRAJECTORIES_SCHEMA), min_version=2),
        TableSpec("edit_pose_tracks", _fixed(EDIT_POSE_TRACKS_SCHEMA)),
        TableSpec("metrics", _fixed(METRICS_SCHEMA)),
    )
}


def _meta(metadata: Mapping[bytes, bytes] | None) -> dict[str, str]:
    return {k.decode(): v.decode() for k, v in (metadata or {}).items()}


def schema_name(schema: pa.Schema) -> str:
    return _meta(schema.metadata)[SCHEMA_NAME_KEY]


def schema_version(schema: pa.Schema) -> int:
    return int(_meta(schema.metadata)[SCHEMA_VERSION_KEY])


def schema_from_metadata(name: str, metadata: Mapping[bytes, bytes] | None, source: str) -> pa.Schema:
    """Expected schema of table ``name`` with the dims recorded in a file's ``metadata``.

    Raises:
        SchemaError: unknown table, or a dim missing / not a valid integer in the metadata.
    """
    if name not in TABLES:
        raise SchemaError(f"{source}: unknown table {name!r}; known: {sorted(TABLES)}")
    spec = TABLES[name]
    meta = _meta(metadata)
    dims: dict[str, int] = {}
    for dim in spec.dims:
        try:
            dims[dim] = int(meta[dim])
        except (KeyError, ValueError):
            raise SchemaError(
                f"{source}: metadata key {dim!r} of table {name!r} is missing or not an integer "
                f"(got {meta.get(dim)!r})"
            ) from None
    try:
        return spec.build(**dims)
    except ValueError as exc:
        raise SchemaError(f"{source}: {exc}") from None


def validate_table(table: pa.Table, schema: pa.Schema, source: str, *, require_metadata: bool = True) -> None:
    """Check ``table`` against ``schema``; raise one ``SchemaError`` listing every problem.

    Checks: ``schema_name`` (and ``schema_version`` not newer than supported nor older than the
    oldest readable), each expected column present with the expected type (fixed widths named
    explicitly), no unexpected columns, and no nulls (top-level or inside list values) in
    non-nullable columns.

    Args:
        source: the file (URI) named in the message.
        require_metadata: when False (tables built in memory before writing) missing metadata is
            accepted; present but different metadata is still an error.
    """
    problems = _metadata_problems(_meta(table.schema.metadata), _meta(schema.metadata), require_metadata)
    actual_names = set(table.schema.names)
    older = _older_version(table.schema, schema)
    for field in schema:
        if field.name not in actual_names:
            if field.nullable and older:  # added in a later version: read as nulls (fill_added_columns)
                continue
            problems.append(f"column {field.name!r} is missing (expected {field.type})")
            continue
        actual = table.schema.field(field.name).type
        if actual != field.type:
            problems.append(_type_problem(field.name, actual, field.type))
        elif not field.nullable:
            nulls = _null_count(table.column(field.name))
            if nulls:
                problems.append(f"column {field.name!r} has {nulls} null value(s) but is not nullable")
    extra = [n for n in table.schema.names if n not in set(schema.names)]
    if extra:
        problems.append(f"unexpected column(s) {extra} (not in schema)")
    if problems:
        name = _meta(schema.metadata).get(SCHEMA_NAME_KEY, "?")
        raise SchemaError(f"{source}: does not match schema {name!r}: " + "; ".join(problems))


def _older_version(actual: pa.Schema, expected: pa.Schema) -> bool:
    """The table's ``schema_version`` is older than ``expected``'s (False when either has none)."""
    try:
        return int(_meta(actual.metadata)[SCHEMA_VERSION_KEY]) < schema_version(expected)
    except (KeyError, ValueError):
        return False


def fill_added_columns(table: pa.Table, schema: pa.Schema) -> pa.Table:
    """``table`` with every nullable column of ``schema`` it lacks appended as nulls (a file written before the
    column was added; :func:`validate_table` accepts it only then)."""
    for field in schema:
        if field.name not in table.schema.names and field.nullable:
            table = table.append_column(field, pa.nulls(table.num_rows, field.type))
    return table


def _metadata_problems(actual: dict[str, str], expected: dict[str, str], required: bool) -> list[str]:
    problems: list[str] = []
    name = expected[SCHEMA_NAME_KEY]
    if SCHEMA_NAME_KEY not in actual:
        if required:
            problems.append(f"metadata has no {SCHEMA_NAME_KEY!r} (expected {name!r})")
    elif actual[SCHEMA_NAME_KEY] != name:
        problems.append(f"{SCHEMA_NAME_KEY} is {actual[SCHEMA_NAME_KEY]!r}, expected {name!r}")
    if SCHEMA_VERSION_KEY not in actual:
        if required:
            problems.append(f"metadata has no {SCHEMA_VERSION_KEY!r}")
        return problems
    current = int(expected[SCHEMA_VERSION_KEY])
    oldest = TABLES[name].min_version if name in TABLES else current
    try:
        version = int(actual[SCHEMA_VERSION_KEY])
    except ValueError:
        return [*problems, f"{SCHEMA_VERSION_KEY} {actual[SCHEMA_VERSION_KEY]!r} is not an integer"]
    if version > current:
        problems.append(f"{SCHEMA_VERSION_KEY} {version} is newer than supported version {current} (upgrade simsplat)")
    elif version < oldest:
        problems.append(f"{SCHEMA_VERSION_KEY} {version} is older than the oldest readable version {oldest}")
    return problems


def _type_problem(column: str, actual: pa.DataType, expected: pa.DataType) -> str:
    if (
        pa.types.is_fixed_size_list(actual)
        and pa.types.is_fixed_size_list(expected)
        and actual.value_type == expected.value_type
    ):
        return f"column {column!r} has fixed width {actual.list_size}, expected {expected.list_size}"
    return f"column {column!r} has type {actual}, expected {expected}"


def _is_list(t: pa.DataType) -> bool:
    return pa.types.is_list(t) or pa.types.is_large_list(t) or pa.types.is_fixed_size_list(t)


def _null_count(column: pa.ChunkedArray) -> int:
    """Nulls in ``column`` and in the values of (nested) list columns."""
    total = 0
    for chunk in column.chunks:
        array: pa.Array = chunk
        total += array.null_count
        while _is_list(array.type):
            array = array.flatten()
            total += array.null_count
    return total


# ----------------------------------------------------------------------------- JSON Schema export
def json_schema(schema: pa.Schema) -> dict:
    """JSON Schema (draft 2020-12) of one row of ``schema``, for documentation and external tools."""
    meta = _meta(schema.metadata)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": meta.get(SCHEMA_NAME_KEY, ""),
        "description": f"one row of table {meta.get(SCHEMA_NAME_KEY, '')!r}, schema_version "
        f"{meta.get(SCHEMA_VERSION_KEY, '?')}",
        "type": "object",
        "properties": {field.name: _json_type(field.type) if not field.nullable
                       else {"anyOf": [_json_type(field.type), {"type": "null"}]} for field in schema},
        "required": [field.name for field in schema if not field.nullable],
        "additionalProperties": False,
    }


def _json_type(t: pa.DataType) -> dict:
    if pa.types.is_string(t) or pa.types.is_large_string(t):
        return {"type": "string"}
    if pa.types.is_boolean(t):
        return {"type": "boolean"}
    if pa.types.is_integer(t):
        return {"type": "integer"}
    if pa.types.is_floating(t):
        return {"type": "number"}
    if pa.types.is_fixed_size_list(t):
        return {"type": "array", "items": _json_type(t.value_type), "minItems": t.list_size, "maxItems": t.list_size}
    if pa.types.is_map(t):
        return {"type": "object", "additionalProperties": _json_type(t.item_type)}
    if pa.types.is_list(t) or pa.types.is_large_list(t):
        return {"type": "array", "items": _json_type(t.value_type)}
    raise TypeError(f"no JSON Schema mapping for arrow type {t}")


# ----------------------------------------------------------------------------- column helpers
def vectors_to_arrow(values: np.ndarray, width: int) -> pa.FixedSizeListArray:
    """``[N, width]`` (or anything reshapeable to it) -> ``FixedSizeList<float32>[width]`` array (N rows)."""
    flat = np.ascontiguousarray(np.asarray(values, dtype=np.float32).reshape(-1))
    if flat.size % width:
        raise ValueError(f"cannot split {flat.size} values into rows of width {width}")
    return pa.FixedSizeListArray.from_arrays(pa.array(flat, pa.float32()), width)


def arrow_to_vectors(column: pa.ChunkedArray | pa.Array) -> np.ndarray:
    """``FixedSizeList<float32>[w]`` column -> ``[N, w]`` float32 array."""
    array = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
    width = array.type.list_size
    values = array.flatten().to_numpy(zero_copy_only=False)
    return np.asarray(values, dtype=np.float32).reshape(len(array), width)


def grounding_table_schema(first_column: str) -> pa.Schema:
    """Tables 2 / 3 of a run (``tables/grounding*.parquet``): one row per method (``first_column`` =
    ``"method"``) or feature set (``"features"``); accuracy and vIoU per category, query counts."""
    from simsplat_core.eval.grounding.metrics import CATEGORIES  # imported here: storage loads without the core

    fields: list[tuple[str, pa.DataType]] = [(first_column, pa.string())]
    fields += [(f"{c}_{m}", pa.float64()) for c in CATEGORIES for m in ("acc", "viou")]
    fields += [(f"{c}_queries", pa.int64()) for c in CATEGORIES]
    return _schema(f"grounding_{first_column}", 1, fields)


GROUNDING_OUTCOMES_SCHEMA = _schema(
    "grounding_outcomes",
    1,
    [
        ("method", pa.string()),
        ("seq_id", pa.string()),
        ("query_id", pa.string()),
        ("text", pa.string()),
        ("style", pa.string()),
        ("kind", pa.string()),  # "single" | "group" | "none"
        ("category", pa.string()),  # "vehicle" | "pedestrian"
        ("targets", pa.list_(pa.string())),
        ("predicted", pa.list_(pa.string())),
        ("correct", pa.bool_()),
        ("viou", pa.float64()),
        ("seconds", pa.float64()),
    ],
)



# ----------------------------------------------------------------------------- editing evaluation (run tables)
#: Tables of ``simsplat eval editing`` (columns defined by ``simsplat_core.eval.editing.outcomes``).
EDITING_TABLES: tuple[str, ...] = ("editing", "editing_infeasible", "edit_fidelity", "editing_outcomes")


def editing_table_schema(name: str) -> pa.Schema:
    """Schema of one editing-evaluation table (``EDITING_TABLES``): ``editing`` (method, category, prompts,
    completed, rate), ``editing_infeasible``, ``edit_fidelity`` (method, category, edits, psnr, ssim,
    psnr_unedited, psnr_region, psnr_unedited_region) and ``editing_outcomes`` (one row per method and prompt).

    Raises:
        KeyError: an unknown table name.
    """
    from simsplat_core.eval.editing.outcomes import TABLE_COLUMNS  # imported here: storage loads without the core

    if name not in TABLE_COLUMNS:
        raise KeyError(f"no editing table {name!r}; known: {list(TABLE_COLUMNS)}")
    return _schema(name, 1, list(TABLE_COLUMNS[name]))


# ----------------------------------------------------------------------------- mining evaluation (run tables)
#: Tables of ``simsplat eval mining`` (columns defined by ``simsplat_core.eval.mining``).
MINING_TABLES: tuple[str, ...] = ("mining", "mining_by_category", "mining_stages")


def mining_table_schema(name: str) -> pa.Schema:
    """Schema of one mining-evaluation table (``MINING_TABLES``): ``mining`` (one row per VLM client: prompts,
    accepted, completion, attempts_mean, plausibility_mean, accepted_with_failure, ...), ``mining_by_category``
    (client, category, prompts, accepted, completion, attempts_mean) and ``mining_stages`` (client, stage,
    seconds, share, seconds_per_accepted, accepted_per_hour_per_core).

    Raises:
        KeyError: an unknown table name.
    """
    from simsplat_core.eval import mining  # imported here: storage loads without the core

    columns = {"mining": mining.MINING_COLUMNS, "mining_by_category": mining.MINING_BY_CATEGORY_COLUMNS,
               "mining_stages": mining.MINING_STAGES_COLUMNS}
    if name not in columns:
        raise KeyError(f"no mining table {name!r}; known: {list(columns)}")
    return _schema(name, 1, list(columns[name]))


# ----------------------------------------------------------------------------- motion evaluation (run table)
#: ``schema_version`` of the ``motion`` table.
MOTION_SCHEMA_VERSION = 2  # 2: predictor and refused columns


def motion_table_schema() -> pa.Schema:
    """Schema of ``tables/motion.parquet`` of ``simsplat eval motion``: one row per (dataset, method, predictor);
    columns from ``simsplat_core.eval.refinement.table.MOTION_COLUMNS`` (dataset, method, predictor, scenarios,
    refused, the failure rates, progress, stopped_share, ade_3s / ade_8s nullable, agent_collision,
    agent_offroad).

    A run table like the editing ones (read it with this schema, ``storage.runs.read_motion_table``), not in
    ``TABLES``: its two ADE columns are nullable (undefined for the log row), which the registry's tables never
    are."""
    from simsplat_core.eval.refinement.table import MOTION_COLUMNS  # imported here: storage loads without the core

    metadata = {SCHEMA_NAME_KEY: "motion", SCHEMA_VERSION_KEY: str(MOTION_SCHEMA_VERSION)}
    return pa.schema([pa.field(n, t, nullable=nullable) for n, t, nullable in MOTION_COLUMNS], metadata=metadata)


#: ``schema_version`` of the ``motion_outcomes`` table.
MOTION_OUTCOMES_SCHEMA_VERSION = 1


def motion_outcomes_schema() -> pa.Schema:
    """Schema of ``tables/motion_outcomes.parquet`` of ``simsplat eval motion``: one row per (edit case,
    refinement mode), columns from ``simsplat_core.eval.refinement.table.OUTCOME_COLUMNS`` (case, mode,
    predictor, refusal, failure flags, failed agents and what happened to each, reacting agents, progress,
    seconds). A run table, like ``motion``."""
    from simsplat_core.eval.refinement.table import OUTCOME_COLUMNS  # imported here: storage loads without the core

    metadata = {SCHEMA_NAME_KEY: "motion_outcomes", SCHEMA_VERSION_KEY: str(MOTION_OUTCOMES_SCHEMA_VERSION)}
    return pa.schema([pa.field(n, t, nullable=nullable) for n, t, nullable in OUTCOME_COLUMNS], metadata=metadata)


# ----------------------------------------------------------------------------- search evaluation (run table)
#: ``schema_version`` of the ``search`` table.
SEARCH_SCHEMA_VERSION = 1
#: Columns of ``tables/search.parquet``: ``(name, type, nullable)``; the balanced accuracies are ``nan``-free nulls
#: where undefined.
SEARCH_COLUMNS: tuple[tuple[str, pa.DataType, bool], ...] = (
    ("query", pa.string(), False),
    ("negative", pa.bool_(), False),
    ("timestamp_ba", pa.float64(), True),
    ("log_ba", pa.float64(), True),
    ("hits", pa.int64(), False),
    ("logs_true", pa.int64(), False),
    ("logs_hit", pa.int64(), False),
    ("seconds", pa.float64(), False),
)


def search_table_schema() -> pa.Schema:
    """Schema of ``tables/search.parquet`` (``tasks.search_eval``): one row per query of the search query set --
    query, negative (holds nowhere by the world's ground truth), timestamp_ba, log_ba (RefAV balanced accuracies),
    hits, logs_true / logs_hit (logs containing the scenario / with a hit), seconds (search over all logs)."""
    metadata = {SCHEMA_NAME_KEY: "search", SCHEMA_VERSION_KEY: str(SEARCH_SCHEMA_VERSION)}
    return pa.schema([pa.field(n, t, nullable=nullable) for n, t, nullable in SEARCH_COLUMNS], metadata=metadata)
