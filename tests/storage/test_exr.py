"""EXR renders: canonical channels, bit-exact float32 round trip, zip compression."""

from __future__ import annotations

import numpy as np
import pytest

from storage import (
    MAX_EXACT_ID,
    ArtifactStore,
    CorruptArtifactError,
    read_exr,
    read_exr_header,
    render_channels,
    write_exr,
)

CANONICAL = ["R", "G", "B", "A", "Z", "id"] + [f"feat.{i:02d}" for i in range(8)]


def _render(h: int = 5, w: int = 7, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    depth = rng.uniform(0.1, 500.0, (h, w)).astype(np.float32)
    depth[0, :] = np.inf
    ids = rng.integers(0, 1000, (h, w)).astype(np.int64)
    ids[1, 1], ids[1, 2] = MAX_EXACT_ID, MAX_EXACT_ID - 1
    features = rng.normal(0, 1, (h, w, 8)).astype(np.float32)
    features[2, 2, 3] = np.float32(1e-42)  # subnormal survives too
    return render_channels(
        rgb=rng.random((h, w, 3), dtype=np.float32),
        alpha=rng.random((h, w), dtype=np.float32),
        depth=depth,
        node_id=ids,
        features=features,
    )


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


def test_render_channels_order_and_dtype() -> None:
    channels = _render()
    assert list(channels) == CANONICAL
    assert all(c.dtype == np.float32 and c.shape == (5, 7) for c in channels.values())


def _check_round_trip(store: ArtifactStore) -> None:
    channels = _render()
    write_exr(store, "renders/cam/000001.exr", channels)
    back = read_exr(store, "renders/cam/000001.exr")
    assert list(back) == CANONICAL
    for name in CANONICAL:
        assert back[name].dtype == np.float32 and back[name].shape == (5, 7)
        assert np.array_equal(_bits(back[name]), _bits(channels[name])), name
    assert np.isinf(back["Z"][0]).all()
    assert back["id"][1, 1] == MAX_EXACT_ID and back["id"][1, 2] == MAX_EXACT_ID - 1
    header = read_exr_header(store, "renders/cam/000001.exr")
    assert header["compression"] == "zip"
    assert header["format"] == ["float"]
    assert sorted(header["channels"]) == sorted(CANONICAL)
    assert (header["width"], header["height"]) == (7, 5)


def test_round_trip_bit_exact_local(store: ArtifactStore) -> None:
    _check_round_trip(store)
    assert store.listdir("renders/cam") == ["000001.exr"]  # no temporary left


def test_round_trip_bit_exact_object_store(mock_store: ArtifactStore) -> None:
    _check_round_trip(mock_store)


def test_channel_subsets_and_order_of_input_do_not_matter(store: ArtifactStore) -> None:
    z = np.full((2, 3), np.inf, np.float32)
    write_exr(store, "z.exr", {"Z": z, "feat.10": np.zeros_like(z), "feat.02": np.ones_like(z)})
    assert list(read_exr(store, "z.exr")) == ["Z", "feat.02", "feat.10"]


@pytest.mark.parametrize(
    ("channels", "message"),
    [
        ({"R": np.zeros((2, 2)), "normal": np.zeros((2, 2))}, "unknown EXR channel"),
        ({"R": np.zeros((2, 2)), "G": np.zeros((2, 3))}, "differ in shape"),
        ({"id": np.array([[MAX_EXACT_ID + 1]], np.int64)}, "2\\*\\*24"),
        ({"R": np.zeros((2, 2, 3))}, "must be \\[H, W\\]"),
        ({}, "no channels"),
    ],
)
def test_invalid_channels_are_rejected(store: ArtifactStore, channels, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        write_exr(store, "bad.exr", channels)
    assert not store.exists("bad.exr")


def test_corrupt_and_missing_exr_name_the_file(store: ArtifactStore) -> None:
    store.write_bytes("broken.exr", b"not an exr")
    with pytest.raises(CorruptArtifactError, match="broken.exr"):
        read_exr(store, "broken.exr")
    with pytest.raises(FileNotFoundError, match="absent.exr"):
        read_exr(store, "absent.exr")


def test_half_float_keeps_ids_exact_and_colours_close(tmp_path) -> None:
    store = ArtifactStore(str(tmp_path))
    channels = _render(h=16, w=24, seed=3)
    del channels["Z"]  # depth in half would clip far values; the edit renders leave it out
    write_exr(store, "full.exr", channels)
    write_exr(store, "half.exr", channels, half=True)
    back = read_exr(store, "half.exr")
    assert list(back) == list(channels)
    assert np.array_equal(back["id"], channels["id"])  # float32: ids up to 2**24 exact
    for name in ("R", "G", "B", "A"):
        assert np.abs(back[name] - channels[name]).max() <= 2.0**-11
        assert not np.array_equal(back[name], channels[name])  # really stored as half
    header = read_exr_header(store, "half.exr")
    assert header["format"] == ["float", "half"]
    assert store.size("half.exr") < store.size("full.exr")


def test_valid_mask_is_a_mask_channel_read_back_as_written(store: ArtifactStore) -> None:
    valid = np.ones((5, 7), bool)
    valid[3:, 2:5] = False
    channels = render_channels(rgb=np.zeros((5, 7, 3), np.float32), valid_mask=valid)
    assert list(channels) == ["R", "G", "B", "mask"]
    write_exr(store, "images/cam/000000.exr", channels)
    back = read_exr(store, "images/cam/000000.exr")
    assert np.array_equal(back["mask"] > 0.5, valid) and set(np.unique(back["mask"])) == {0.0, 1.0}
