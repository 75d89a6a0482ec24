"""Asset banks in the store: bit-exact round trip, newest / prefix lookup, atomicity, errors naming file and column."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import torch

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.procedural import procedural_asset
from storage import ArtifactStore, CorruptArtifactError, list_asset_banks, read_asset_bank, write_asset_bank
from storage.assets import bank_dir, read_asset_index, read_bank_manifest
from tests.simsplat_core.editing.assets.fixtures import mesh_vehicle, walking_pedestrian


@pytest.fixture(scope="module")
def bank() -> AssetBank:
    return AssetBank.from_assets([mesh_vehicle("t.red-sedan"), walking_pedestrian(asset_id="t.ped"),
                                  procedural_asset("barrel", "orange")])


def _assert_same(a: AssetBank, b: AssetBank) -> None:
    assert a.bank_hash == b.bank_hash and a.ids == b.ids
    for x, y in zip(a.assets, b.assets):
        for name in ("asset_id", "category", "subtype", "caption", "color", "size", "source_seq", "source_object",
                     "attributes"):
            assert getattr(x, name) == getattr(y, name), (x.asset_id, name)
        xs, ys = dict(x.gaussians.named_tensors()), dict(y.gaussians.named_tensors())
        assert list(xs) == list(ys), x.asset_id
        for name, tensor in xs.items():
            assert tensor.dtype == ys[name].dtype == torch.float32
            assert torch.equal(tensor, ys[name]), (x.asset_id, name)  # bit for bit
        for name in ("deform_frames", "deform_arc_length"):
            u, v = getattr(x, name), getattr(y, name)
            assert (u is None and v is None) or (u.dtype == v.dtype and np.array_equal(u, v)), (x.asset_id, name)


def test_a_bank_round_trips_bit_for_bit(store: ArtifactStore, bank: AssetBank) -> None:
    assert write_asset_bank(store, bank, extra_files={"contact_sheet.png": b"png"}) == bank.bank_hash
    back = read_asset_bank(store)
    _assert_same(bank, back)
    ped = back.get("t.ped")
    assert ped.offsets is not None and ped.walked_m == pytest.approx(3.9)
    files = set(store.walk(bank_dir(bank.bank_hash)))
    assert {"assets.parquet", "gaussians/t.red-sedan.parquet", "gaussians/t.ped.parquet",
            "deform/t.ped.parquet", "contact_sheet.png", "_SUCCESS.json"} <= files
    assert "deform/t.red-sedan.parquet" not in files
    manifest = read_bank_manifest(store, bank.bank_hash)
    assert manifest["assets"] == 3 and manifest["by_category"] == {"vehicle": 1, "pedestrian": 1, "static": 1}
    bank_hash, rows = read_asset_index(store)
    assert bank_hash == bank.bank_hash and [r["asset_id"] for r in rows] == bank.ids


def test_the_object_store_path_round_trips_too(mock_store: ArtifactStore, bank: AssetBank) -> None:
    write_asset_bank(mock_store, bank)
    _assert_same(bank, read_asset_bank(mock_store, bank.bank_hash[:10]))


def test_newest_bank_prefixes_and_rewrites(store: ArtifactStore, bank: AssetBank,
                                           snapshot: Callable[[Path], dict[str, str]], tmp_path: Path) -> None:
    other = AssetBank.from_assets([procedural_asset("traffic cone", "yellow")])
    write_asset_bank(store, bank)
    time.sleep(0.01)
    write_asset_bank(store, other)
    assert list_asset_banks(store) == [bank.bank_hash, other.bank_hash]
    assert read_asset_bank(store).bank_hash == other.bank_hash  # the newest
    assert read_asset_bank(store, bank.bank_hash[:8]).bank_hash == bank.bank_hash
    before = snapshot(tmp_path / "root")
    write_asset_bank(store, bank)  # already complete: nothing is written
    assert snapshot(tmp_path / "root") == before
    with pytest.raises(FileNotFoundError, match="no complete asset bank"):
        read_asset_bank(store, "deadbeef")


def test_an_empty_store_says_how_to_build_a_bank(store: ArtifactStore) -> None:
    with pytest.raises(FileNotFoundError, match="simsplat assets build"):
        read_asset_bank(store)


def test_a_failed_write_leaves_nothing(store: ArtifactStore, bank: AssetBank, monkeypatch) -> None:
    calls = []
    real = ArtifactStore.write_table

    def failing(self, relpath, table, schema):
        calls.append(relpath)
        if len(calls) == 3:
            raise OSError("disk full")
        return real(self, relpath, table, schema)

    monkeypatch.setattr(ArtifactStore, "write_table", failing)
    with pytest.raises(OSError, match="disk full"):
        write_asset_bank(store, bank)
    assert store.listdir("assets") == [] and list_asset_banks(store) == []


def test_assets_with_scene_features_are_not_stored(store: ArtifactStore) -> None:
    asset = procedural_asset("traffic cone")
    asset.gaussians.features = torch.zeros(asset.num_gaussians, 4)
    with pytest.raises(ValueError, match="features"):
        write_asset_bank(store, AssetBank.from_assets([asset]))


def _rewrite_assets_table(store: ArtifactStore, bank_hash: str, edit: Callable[[pa.Table], pa.Table]) -> str:
    path = f"{bank_dir(bank_hash)}/assets.parquet"
    table = store.read_table(path, "assets")
    with store.open_output(path) as out:
        pq.write_table(edit(table), out)
    return path


def _set(table: pa.Table, column: str, row: int, value) -> pa.Table:
    values = table.column(column).to_pylist()
    values[row] = value
    return table.set_column(table.schema.get_field_index(column), column,
                            pa.array(values, table.schema.field(column).type))


@pytest.mark.parametrize(("column", "row", "value", "message"), [
    ("category", 0, "plane", r"column 'category', row 0: 'plane' is not one of"),
    ("num_gaussians", 2, 7, r"column 'num_gaussians', row 2: 7 but .*gaussians/proc\.barrel\.orange\.parquet has"),
    ("deform_frames", 1, [0, 1, 2], r"column 'deform_frames', row 1: .*do not match the frames of .*deform/t\.ped"),
    ("bank_hash", 0, "ab" * 8, r"column 'bank_hash', row 0"),
    ("asset_id", 1, "t.red-sedan", r"column 'asset_id': .*duplicate asset ids"),
])
def test_inconsistent_tables_name_the_file_and_the_column(store: ArtifactStore, bank: AssetBank, column: str,
                                                         row: int, value, message: str) -> None:
    write_asset_bank(store, bank)
    path = _rewrite_assets_table(store, bank.bank_hash, lambda t: _set(t, column, row, value))
    with pytest.raises(CorruptArtifactError, match=message) as error:
        read_asset_bank(store)
    assert str(error.value).startswith(store.uri(path))  # the file first, then the column


def test_a_missing_gaussians_file_is_named(store: ArtifactStore, bank: AssetBank) -> None:
    write_asset_bank(store, bank)
    store.delete(f"{bank_dir(bank.bank_hash)}/gaussians/t.ped.parquet")
    with pytest.raises(FileNotFoundError, match=r"gaussians/t\.ped\.parquet"):
        read_asset_bank(store)
