"""Persist asset banks under ``assets/<bank_hash>/`` and read them back.

Layout of one bank (written inside one ``staged_directory``, so it appears complete or not at all)::

    assets/<bank_hash>/assets.parquet               one row per asset (``schemas.ASSETS_SCHEMA``)
                       gaussians/<asset_id>.parquet  the asset's Gaussians in its box frame (``gaussians`` table,
                                                     ``scene_id`` = ``assets/<bank_hash>/<asset_id>``, node 0)
                       deform/<asset_id>.parquet     deformable assets: per-frame offsets (``deformations`` table)
                       _SUCCESS.json                 manifest: key (= bank hash), counts, bytes, provenance

Every array is float32 (sizes and walked distances included; ``Asset`` keeps them float32-representable),
so a bank round-trips bit for bit. Reading checks the tables against their schemas and the files against
each other (row counts, deform frames), raising errors that name the file and the column.
"""

from __future__ import annotations

import datetime
import logging
import re
from collections import Counter
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa

from storage.errors import CorruptArtifactError
from storage.markers import is_done, mark_done, read_marker
from storage.scenes import deformation_table, gaussian_columns, gaussians_table, read_deformation_table
from storage.schemas.base import arrow_to_vectors, schema_version, vectors_to_arrow
from storage.schemas.edits import ASSETS_SCHEMA
from storage.schemas.scenes import DEFORMATIONS_SCHEMA
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

ASSETS_DIR = "assets"
MANIFEST_FORMAT = "simsplat.asset_bank"
#: Version of this on-disk layout (part of a bank's content key, see ``tasks.assets``).
ASSET_BANK_FORMAT_VERSION = 1
_HASH = re.compile(r"^[0-9a-f]{8,64}$")
_CATEGORIES = ("vehicle", "pedestrian", "static")


def _check_hash(bank_hash: str) -> str:
    if not _HASH.match(bank_hash or ""):
        raise ValueError(f"bank hash {bank_hash!r} must be 8-64 lowercase hex digits")
    return bank_hash


def bank_dir(bank_hash: str) -> str:
    """``assets/<bank_hash>``."""
    return join_relpath(ASSETS_DIR, _check_hash(bank_hash))


def gaussians_relpath(asset_id: str) -> str:
    return f"gaussians/{asset_id}.parquet"


def deform_relpath(asset_id: str) -> str:
    return f"deform/{asset_id}.parquet"


def read_bank_manifest(store: ArtifactStore, bank_hash: str) -> dict | None:
    """The manifest of a complete bank, or ``None``."""
    marker = read_marker(store, bank_dir(bank_hash))
    return marker if marker is not None and marker["key"] == bank_hash else None


def bank_exists(store: ArtifactStore, bank_hash: str) -> bool:
    return read_bank_manifest(store, bank_hash) is not None


def list_asset_banks(store: ArtifactStore) -> list[str]:
    """Hashes of the complete banks in the store, oldest first (by the manifest's ``written_at``)."""
    found = []
    for name in store.listdir(ASSETS_DIR):
        if _HASH.match(name):
            manifest = read_bank_manifest(store, name)
            if manifest is not None:
                found.append((str(manifest.get("written_at", "")), name))
    return [name for _, name in sorted(found)]


def resolve_bank_hash(store: ArtifactStore, bank_hash: str | None = None) -> str:
    """The full hash of a complete bank: the newest when ``bank_hash`` is ``None``, else the one it names
    (a unique prefix of at least 8 hex digits is enough).

    Raises:
        FileNotFoundError: no (matching) complete bank, naming the directory.
        ValueError: an ambiguous prefix.
    """
    complete = list_asset_banks(store)
    if bank_hash is None:
        if not complete:
            raise FileNotFoundError(f"{store.uri(ASSETS_DIR)}: no complete asset bank (run `simsplat assets build`)")
        return complete[-1]
    matches = [h for h in complete if h.startswith(_check_hash(bank_hash))]
    if not matches:
        raise FileNotFoundError(f"{store.uri(join_relpath(ASSETS_DIR, bank_hash))}: no complete asset bank; "
                                f"complete banks: {[h[:12] for h in complete]}")
    if len(matches) > 1:
        raise ValueError(f"{store.uri(ASSETS_DIR)}: bank hash prefix {bank_hash!r} is ambiguous: "
                         f"{[h[:12] for h in matches]}")
    return matches[0]


# ----------------------------------------------------------------------------- write
def _assets_table(bank: Any) -> pa.Table:
    assets = bank.assets
    n = len(assets)
    frames = [[] if a.deform_frames is None else a.deform_frames.tolist() for a in assets]
    arcs = [np.zeros(0, np.float32) if a.deform_arc_length is None else a.deform_arc_length for a in assets]
    arc_values = np.concatenate(arcs) if n else np.zeros(0, np.float32)
    arc_offsets = np.concatenate([[0], np.cumsum([len(x) for x in arcs])]).astype(np.int32)
    return pa.table({
        "bank_hash": pa.array([bank.bank_hash] * n, pa.string()),
        "asset_id": pa.array([a.asset_id for a in assets], pa.string()),
        "category": pa.array([a.category for a in assets], pa.string()),
        "subtype": pa.array([a.subtype for a in assets], pa.string()),
        "caption": pa.array([a.caption for a in assets], pa.string()),
        "color": pa.array([a.color for a in assets], pa.string()),
        "size": vectors_to_arrow(np.asarray([a.size for a in assets], np.float32).reshape(n, 3), 3),
        "source_seq": pa.array([a.source_seq for a in assets], pa.string()),
        "source_object": pa.array([a.source_object for a in assets], pa.string()),
        "num_gaussians": pa.array([a.num_gaussians for a in assets], pa.int64()),
        "gaussians_uri": pa.array([gaussians_relpath(a.asset_id) for a in assets], pa.string()),
        "deform_uri": pa.array([deform_relpath(a.asset_id) if a.deformable else "" for a in assets], pa.string()),
        "deform_frames": pa.array(frames, pa.list_(pa.int64())),
        "deform_arc_length": pa.ListArray.from_arrays(pa.array(arc_offsets), pa.array(arc_values, pa.float32())),
        "attributes": pa.array([list(a.attributes.items()) for a in assets], pa.map_(pa.string(), pa.string())),
    })


def _gaussian_columns(asset: Any) -> dict[str, np.ndarray]:
    gs = asset.gaussians
    return {"node_id": np.zeros(len(gs), np.int32), "mean": gs.means.numpy(), "log_scale": gs.log_scales.numpy(),
            "quat": gs.quats.numpy(), "color": gs.colors.numpy(), "opacity_logit": gs.opacity_logits.numpy()}


def write_asset_bank(store: ArtifactStore, bank: Any, *, provenance: Mapping[str, Any] | None = None,
                     extra_files: Mapping[str, bytes] | None = None, overwrite: bool = False) -> str:
    """Write ``bank`` (a ``simsplat_core.editing.assets.bank.AssetBank``) atomically under ``assets/<bank_hash>/``;
    returns the bank hash. A complete bank with that hash is kept as it is unless ``overwrite``.

    Args:
        provenance: JSON-serialisable facts stored in the manifest (sources, config, versions).
        extra_files: ``name -> bytes`` written into the bank directory with it (e.g. ``contact_sheet.png``).

    Raises:
        ValueError: a malformed hash, or an asset with per-Gaussian features (they belong to one scene).
        SchemaError: a table does not match its schema (naming the file and the column).
    """
    rel = bank_dir(bank.bank_hash)
    if not overwrite and is_done(store, rel, bank.bank_hash):
        logger.info("asset bank %s already complete, skipping write", store.uri(rel))
        return bank.bank_hash
    with_features = [a.asset_id for a in bank.assets if a.gaussians.features is not None]
    if with_features:
        raise ValueError(f"assets {with_features[:3]} carry per-Gaussian features (a scene's language latents); "
                         "drop them before storing")
    with store.staged_directory(rel) as tmp:
        path = join_relpath(tmp, "assets.parquet")
        store.write_table(path, _assets_table(bank), ASSETS_SCHEMA)
        nbytes = store.size(path)
        for asset in bank.assets:
            scene_id = f"{ASSETS_DIR}/{bank.bank_hash}/{asset.asset_id}"
            table, schema = gaussians_table(scene_id, _gaussian_columns(asset))
            path = join_relpath(tmp, gaussians_relpath(asset.asset_id))
            store.write_table(path, table, schema)
            nbytes += store.size(path)
            if asset.deformable:
                offsets = asset.offsets.numpy().transpose(1, 0, 2)  # [T_h, N, 3]
                path = join_relpath(tmp, deform_relpath(asset.asset_id))
                store.write_table(path, deformation_table(scene_id, 0, asset.deform_frames, offsets),
                                  DEFORMATIONS_SCHEMA)
                nbytes += store.size(path)
        for name, data in (extra_files or {}).items():
            store.write_bytes(join_relpath(tmp, name), data)
        manifest = {
            "format": MANIFEST_FORMAT,
            "format_version": ASSET_BANK_FORMAT_VERSION,
            "assets": len(bank.assets),
            "by_category": dict(Counter(a.category for a in bank.assets)),
            "gaussians": int(sum(a.num_gaussians for a in bank.assets)),
            "bytes": int(nbytes),
            "schema_version": schema_version(ASSETS_SCHEMA),
            "written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds"),
            "files": sorted(extra_files or {}),
            "provenance": dict(provenance or {}),
        }
        mark_done(store, tmp, bank.bank_hash, manifest)
    logger.info("wrote asset bank %s (%d assets)", store.uri(rel), len(bank.assets))
    return bank.bank_hash


# ----------------------------------------------------------------------------- read
#: Columns of ``read_asset_index`` rows (the assets table less its per-frame lists).
INDEX_COLUMNS = ("asset_id", "category", "subtype", "caption", "color", "size", "source_seq", "source_object",
                 "num_gaussians", "attributes")


def read_asset_index(store: ArtifactStore, bank_hash: str | None = None) -> tuple[str, list[dict[str, Any]]]:
    """``(bank hash, rows)``: one dict per asset of a bank's ``assets.parquet`` (``INDEX_COLUMNS``; ``size``
    a list of three floats, ``attributes`` a dict), without reading any Gaussians.

    Raises:
        FileNotFoundError, SchemaError, CorruptArtifactError: as ``read_asset_bank``.
    """
    full = resolve_bank_hash(store, bank_hash)
    table = store.read_table(join_relpath(bank_dir(full), "assets.parquet"), ASSETS_SCHEMA)
    rows = table.select(list(INDEX_COLUMNS)).to_pylist()
    for row in rows:
        row["attributes"] = dict(row["attributes"])
    return full, rows


def _bad(store: ArtifactStore, path: str, column: str, row: int, message: str) -> CorruptArtifactError:
    return CorruptArtifactError(f"{store.uri(path)}: column {column!r}, row {row}: {message}")


def read_asset_bank(store: ArtifactStore, bank_hash: str | None = None) -> Any:
    """Read a complete bank (the newest when ``bank_hash`` is ``None``; a unique prefix is enough) as an
    ``AssetBank``.

    Raises:
        FileNotFoundError: no complete bank (or a file of it is missing), naming the path.
        SchemaError, CorruptArtifactError: a file does not decode, validate or agree with the assets table,
            naming the file and the column.
    """
    import torch  # noqa: PLC0415  # slow (as the core's modules): only when a bank is read

    from simsplat_core.editing.assets.bank import Asset, AssetBank  # noqa: PLC0415  # imports torch, see above
    from simsplat_core.scene.gaussians import GaussianSet  # noqa: PLC0415  # imports torch, see above
    from simsplat_core.scene.nodes import OFFSETS  # noqa: PLC0415  # imports torch, see above

    full = resolve_bank_hash(store, bank_hash)
    rel = bank_dir(full)
    table_path = join_relpath(rel, "assets.parquet")
    table = store.read_table(table_path, ASSETS_SCHEMA)
    sizes = arrow_to_vectors(table.column("size"))
    arcs = table.column("deform_arc_length").to_pylist()
    assets = []
    for row, record in enumerate(table.drop_columns(["size", "deform_arc_length"]).to_pylist()):
        if record["bank_hash"] != full:
            raise _bad(store, table_path, "bank_hash", row, f"{record['bank_hash']!r} is not the bank's hash {full!r}")
        if record["category"] not in _CATEGORIES:
            raise _bad(store, table_path, "category", row, f"{record['category']!r} is not one of {_CATEGORIES}")
        g_path = join_relpath(rel, record["gaussians_uri"])
        columns = gaussian_columns(store.read_table(g_path, "gaussians"))
        if len(columns["mean"]) != record["num_gaussians"]:
            raise _bad(store, table_path, "num_gaussians", row, f"{record['num_gaussians']} but {store.uri(g_path)} "
                       f"has {len(columns['mean'])} rows")
        t = lambda a: torch.as_tensor(np.array(a, dtype=np.float32))  # noqa: E731  # a writable copy
        gs = GaussianSet(t(columns["mean"]), t(columns["log_scale"]), t(columns["quat"]), t(columns["color"]),
                         t(columns["opacity_logit"]))
        deform: dict[str, np.ndarray] = {}
        if record["deform_uri"]:
            d_path = join_relpath(rel, record["deform_uri"])
            frames, offsets = read_deformation_table(store, d_path)
            expected = np.asarray(record["deform_frames"], np.int64)
            if not np.array_equal(frames, expected):
                raise _bad(store, table_path, "deform_frames", row, f"{expected.tolist()[:5]}... do not match the "
                           f"frames of {store.uri(d_path)} ({frames.tolist()[:5]}...)")
            if offsets.shape[1] != len(gs):
                raise _bad(store, table_path, "num_gaussians", row, f"{len(gs)} but {store.uri(d_path)} has offsets "
                           f"of {offsets.shape[1]} Gaussians")
            gs.extras[OFFSETS] = t(np.ascontiguousarray(offsets.transpose(1, 0, 2)))
            deform = {"deform_frames": frames, "deform_arc_length": np.asarray(arcs[row], np.float32)}
        try:
            assets.append(Asset(asset_id=record["asset_id"], category=record["category"], subtype=record["subtype"],
                                caption=record["caption"], color=record["color"],
                                size=(float(sizes[row, 0]), float(sizes[row, 1]), float(sizes[row, 2])),
                                source_seq=record["source_seq"], source_object=record["source_object"],
                                gaussians=gs, attributes=dict(record["attributes"]), **deform))
        except ValueError as exc:
            raise CorruptArtifactError(f"{store.uri(table_path)}: row {row} ({record['asset_id']!r}): {exc}") from exc
    try:
        bank = AssetBank(tuple(assets), full)
    except ValueError as exc:
        raise CorruptArtifactError(f"{store.uri(table_path)}: column 'asset_id': {exc}") from exc
    logger.debug("read asset bank %s (%d assets)", store.uri(rel), len(bank))
    return bank


__all__ = ["ASSETS_DIR", "ASSET_BANK_FORMAT_VERSION", "INDEX_COLUMNS", "bank_dir", "bank_exists", "list_asset_banks",
           "read_asset_bank", "read_asset_index", "read_bank_manifest", "resolve_bank_hash", "write_asset_bank"]
