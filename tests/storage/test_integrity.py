"""``storage.integrity``: what ``mark_done`` records of a directory, and every kind of disagreement ``check`` finds,
each naming its file."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pytest

import storage.integrity as integrity
from storage import ArtifactStore, intact_marker, is_done, mark_done, read_marker
from storage.integrity import INTEGRITY_KEY, check
from storage.markers import MARKER_NAME
from storage.schemas.runs import METRICS_SCHEMA

KEY = "k" * 64


def _metrics(n: int) -> pa.Table:
    return pa.table({"run_id": ["r"] * n, "seq_id": ["s"] * n, "stage": ["x"] * n, "name": [f"m{i}" for i in range(n)],
                     "value": [float(i) for i in range(n)], "unit": [""] * n})


@pytest.fixture()
def store(tmp_path: Path) -> ArtifactStore:
    store = ArtifactStore(tmp_path)
    with store.staged_directory("a") as tmp:
        store.write_table(f"{tmp}/metrics.parquet", _metrics(3), METRICS_SCHEMA)
        store.write_bytes(f"{tmp}/big/blob.bin", b"b" * 64)
        store.write_bytes(f"{tmp}/.hidden.lock", b"")
        mark_done(store, tmp, KEY, {"tables": {"metrics": {"rows": 3}}, "by_node": {7: 1, 10: 2}})
    return store


def _problems(store: ArtifactStore, **kw) -> list[str]:
    return check(store, "a", read_marker(store, "a"), MARKER_NAME, **kw)


def test_a_sealed_directory_is_intact_and_lists_every_file_but_hidden_ones(store: ArtifactStore) -> None:
    files = read_marker(store, "a")[INTEGRITY_KEY]["files"]
    assert sorted(files) == ["big/blob.bin", "metrics.parquet"]
    assert files["big/blob.bin"]["bytes"] == 64 and len(files["big/blob.bin"]["sha256"]) == 64
    assert _problems(store) == [] and is_done(store, "a", KEY) and not is_done(store, "a", "other")


def test_large_files_are_checked_by_size_only(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(integrity, "CHECKSUM_MAX_BYTES", 10)
    store = ArtifactStore(tmp_path)
    with store.staged_directory("a") as tmp:
        store.write_bytes(f"{tmp}/blob.bin", b"b" * 64)
        mark_done(store, tmp, KEY)
    assert read_marker(store, "a")[INTEGRITY_KEY]["files"]["blob.bin"] == {"bytes": 64}
    (tmp_path / "a" / "blob.bin").write_bytes(b"c" * 64)  # same size: not seen before the file is decoded
    assert _problems(store) == []


@pytest.mark.parametrize(("damage", "named"), [
    (lambda root: (root / "big" / "blob.bin").write_bytes(b"c" * 64), "big/blob.bin: sha256"),
    (lambda root: (root / "big" / "blob.bin").write_bytes(b"b" * 10), "blob.bin: 10 bytes, the manifest recorded 64"),
    (lambda root: (root / "big" / "blob.bin").unlink(), "big/blob.bin: missing"),
    (lambda root: (root / "metrics.parquet").write_bytes((root / "metrics.parquet").read_bytes()[:100]),
     "metrics.parquet: not a readable Parquet file"),
    (lambda root: (root / MARKER_NAME).write_text((root / MARKER_NAME).read_text().replace('"rows": 3', '"rows": 4')),
     f"{MARKER_NAME}: the manifest does not match its recorded sha256"),
])
def test_each_disagreement_names_its_file(store: ArtifactStore, damage, named: str,
                                          caplog: pytest.LogCaptureFixture) -> None:
    damage(Path(store.root) / "a")
    problems = _problems(store)
    assert any(named in p and p.startswith(store.root) for p in problems), problems
    assert intact_marker(store, "a", KEY) is None and named in caplog.text and "will be recomputed" in caplog.text
    assert _problems(store, checksums=False) == [p for p in problems if ": sha256 " not in p]


def test_a_manifest_from_before_checksums_is_checked_by_its_tables(tmp_path: Path) -> None:
    store = ArtifactStore(tmp_path)
    store.write_table("a/metrics.parquet", _metrics(3), METRICS_SCHEMA)
    size = store.size("a/metrics.parquet")
    store.write_json(f"a/{MARKER_NAME}", {"key": KEY, "tables": {"metrics": {"rows": 3, "bytes": size}}})
    assert _problems(store) == [] and is_done(store, "a", KEY)
    store.write_json(f"a/{MARKER_NAME}", {"key": KEY, "tables": {"metrics": {"rows": 2, "bytes": size}}})
    assert _problems(store) == [f"{store.uri('a/metrics.parquet')}: 3 rows, the manifest counts 2"]
    store.write_json(f"a/{MARKER_NAME}", {"key": KEY, "tables": {"metrics": {"rows": 3, "bytes": size + 1}}})
    assert _problems(store) == [f"{store.uri('a/metrics.parquet')}: {size} bytes, the manifest recorded {size + 1}"]


def test_the_integrity_key_is_reserved(store: ArtifactStore) -> None:
    with pytest.raises(ValueError, match="reserved"):
        mark_done(store, "b", KEY, {INTEGRITY_KEY: {}})
