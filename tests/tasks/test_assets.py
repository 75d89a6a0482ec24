"""The asset-bank task: sources from the store, cut-outs + procedural statics, resumable by content key."""

from __future__ import annotations

from pathlib import Path

import pytest

from simsplat_core.editing.assets.cutout import CutoutConfig
from simsplat_core.editing.assets.procedural import STATIC_KINDS
from storage import ArtifactStore, list_asset_banks, read_asset_bank
from tasks.assets import asset_sources, bank_key, build_asset_bank
from tests.simsplat_core.editing.assets.fixtures import TINY_SCENE_HASH, tiny_store

#: The tiny log has 4 frames and grey random-initialised boxes: a filter that lets them through.
LENIENT = CutoutConfig(min_visible_frames=1, min_gaussians=50, min_coverage=0.0)


@pytest.fixture(scope="module")
def store_root(tmp_path_factory) -> tuple[str, str]:
    return tiny_store(tmp_path_factory.mktemp("assets") / "store")


def test_sources_are_the_newest_scenes(store_root) -> None:
    root, seq_id = store_root
    store = ArtifactStore(root)
    (source,) = asset_sources(store)
    assert (source.seq_id, source.scene_hash, source.language) == (seq_id, TINY_SCENE_HASH, None)
    with pytest.raises(ValueError, match=r"no reconstructed scene of \['synth-000009'\]"):
        asset_sources(store, ["synth-000009"])


def test_build_then_skip_then_rebuild_with_another_filter(store_root) -> None:
    root, seq_id = store_root
    built = build_asset_bank.fn(root, config=LENIENT)
    assert not built.skipped and built.sheet_uri.endswith("contact_sheet.png") and Path(built.sheet_uri).is_file()
    bank = read_asset_bank(ArtifactStore(root), built.bank_hash)
    cut = [a for a in bank.assets if a.source_seq == seq_id]
    assert cut and {a.category for a in cut} <= {"vehicle", "pedestrian"}
    assert all(a.caption and a.color != "unknown" for a in cut)  # captions from the log's attributes
    assert sum(a.procedural for a in bank.assets) == sum(len(k.colors) for k in STATIC_KINDS.values())
    assert any(line.startswith(f"{seq_id}: kept") for line in built.report)
    assert built.by_category["static"] == sum(len(k.colors) for k in STATIC_KINDS.values())
    again = build_asset_bank.fn(root, config=LENIENT)
    assert again.skipped and again.bank_hash == built.bank_hash and again.assets == built.assets
    strict = build_asset_bank.fn(root, sheet=False)  # the default filter: a 4-frame log gives no cut-out
    assert strict.bank_hash != built.bank_hash and strict.sheet_uri == ""
    assert strict.by_category == {"static": built.by_category["static"]}
    assert list_asset_banks(ArtifactStore(root)) == [built.bank_hash, strict.bank_hash]
    assert bank_key(asset_sources(ArtifactStore(root)), LENIENT) == built.bank_hash
