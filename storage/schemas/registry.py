"""The registry of persisted tables: each table's name, how its schema is built (with the integer dims read from
the file metadata) and the oldest version still read."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import pyarrow as pa

from storage.errors import SchemaError
from storage.schemas.base import metadata_strings, schema_version
from storage.schemas.edits import ASSETS_SCHEMA, EDIT_POSE_TRACKS_SCHEMA, EDITS_SCHEMA, TRAJECTORIES_SCHEMA
from storage.schemas.language import NODE_LANGUAGE_SCHEMA
from storage.schemas.logs import EGO_POSES_SCHEMA, FRAMES_SCHEMA, MAP_FEATURES_SCHEMA, OBJECTS_SCHEMA, TRACKS_SCHEMA
from storage.schemas.runs import METRICS_SCHEMA
from storage.schemas.scenes import DEFORMATIONS_SCHEMA, NODE_POSES_SCHEMA, gaussians_schema, nodes_schema


@dataclass(frozen=True)
class StoredTable:
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


TABLES: dict[str, StoredTable] = {
    spec.name: spec
    for spec in (
        StoredTable("frames", _fixed(FRAMES_SCHEMA)),
        StoredTable("ego_poses", _fixed(EGO_POSES_SCHEMA)),
        StoredTable("tracks", _fixed(TRACKS_SCHEMA)),
        StoredTable("objects", _fixed(OBJECTS_SCHEMA)),
        StoredTable("map_features", _fixed(MAP_FEATURES_SCHEMA)),
        StoredTable("gaussians", gaussians_schema, dims=("feature_dim", "color_dim")),
        StoredTable("nodes", nodes_schema, dims=("dim",)),
        StoredTable("node_poses", _fixed(NODE_POSES_SCHEMA)),
        StoredTable("node_language", _fixed(NODE_LANGUAGE_SCHEMA)),
        StoredTable("deformations", _fixed(DEFORMATIONS_SCHEMA)),
        StoredTable("assets", _fixed(ASSETS_SCHEMA)),
        StoredTable("edits", _fixed(EDITS_SCHEMA)),
        StoredTable("trajectories", _fixed(TRAJECTORIES_SCHEMA), min_version=2),
        StoredTable("edit_pose_tracks", _fixed(EDIT_POSE_TRACKS_SCHEMA)),
        StoredTable("metrics", _fixed(METRICS_SCHEMA)),
    )
}



def schema_from_metadata(name: str, metadata: Mapping[bytes, bytes] | None, source: str) -> pa.Schema:
    """Expected schema of table ``name`` with the dims recorded in a file's ``metadata``.

    Raises:
        SchemaError: unknown table, or a dim missing / not a valid integer in the metadata.
    """
    if name not in TABLES:
        raise SchemaError(f"{source}: unknown table {name!r}; known: {sorted(TABLES)}")
    spec = TABLES[name]
    meta = metadata_strings(metadata)
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

