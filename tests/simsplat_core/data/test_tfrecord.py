"""TFRecord framing: CRC32C, round trip, and corruption detection."""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError, load_waymo_frames
from simsplat_core.data.crc32c import IMPLEMENTATION, crc32c, crc32c_python, masked_crc32c
from simsplat_core.data.tfrecord import encode_tfrecord, iter_tfrecords

WAYMO_FRAME = Path("waymo") / "pvps_data_one_frame.tfrecord"


def _masked_reference(data: bytes) -> int:
    crc = crc32c_python(data)
    return ((((crc >> 15) | (crc << 17)) & 0xFFFFFFFF) + 0xA282EAD8) & 0xFFFFFFFF


def _write_tfrecord(path: Path, payloads: list[bytes]) -> None:
    """A tiny independent TFRecord writer (reference CRC), used to build test files."""
    with path.open("wb") as fh:
        for data in payloads:
            length = struct.pack("<Q", len(data))
            fh.write(length + struct.pack("<I", _masked_reference(length)))
            fh.write(data + struct.pack("<I", _masked_reference(data)))


def test_crc32c_known_vectors() -> None:
    assert crc32c(b"123456789") == 0xE3069283
    assert crc32c_python(b"123456789") == 0xE3069283
    assert crc32c(b"") == 0
    assert crc32c(bytes(32)) == 0x8A9136AA  # RFC 3720 B.4: 32 bytes of zeros


def test_fast_crc_matches_reference() -> None:
    data = np.random.default_rng(0).integers(0, 256, 5000, dtype=np.uint8).tobytes()
    assert crc32c(data) == crc32c_python(data), IMPLEMENTATION
    assert masked_crc32c(data) == _masked_reference(data)


def test_numba_fallback_matches_reference() -> None:
    pytest.importorskip("numba")
    from simsplat_core.data.crc32c import _numba_crc32c

    fallback = _numba_crc32c()
    assert fallback is not None
    data = np.random.default_rng(1).integers(0, 256, 3000, dtype=np.uint8).tobytes()
    assert fallback(data) == crc32c_python(data)
    assert fallback(b"123456789") == 0xE3069283


def test_two_record_round_trip(tmp_path: Path) -> None:
    payloads = [b"first record", bytes(range(256)) * 3]
    path = tmp_path / "two.tfrecord"
    _write_tfrecord(path, payloads)
    records = list(iter_tfrecords(path))
    assert [r.data for r in records] == payloads
    assert [r.index for r in records] == [0, 1]
    assert records[1].offset == 8 + 4 + len(payloads[0]) + 4
    assert b"".join(encode_tfrecord(p) for p in payloads) == path.read_bytes()


def test_empty_file_has_no_records(tmp_path: Path) -> None:
    path = tmp_path / "empty.tfrecord"
    path.write_bytes(b"")
    assert list(iter_tfrecords(path)) == []


def test_reader_is_lazy_and_reports_the_bad_record(tmp_path: Path) -> None:
    path = tmp_path / "three.tfrecord"
    _write_tfrecord(path, [b"a" * 10, b"b" * 20, b"c" * 30])
    raw = bytearray(path.read_bytes())
    second = 8 + 4 + 10 + 4
    raw[second + 12 + 5] ^= 0x01  # a data byte of record 1
    path.write_bytes(bytes(raw))
    it = iter_tfrecords(path)
    assert next(it).data == b"a" * 10
    with pytest.raises(CorruptLogError) as info:
        next(it)
    err = info.value
    assert err.record_index == 1 and err.offset == second
    assert str(path) in str(err) and "record 1" in str(err) and f"byte offset {second}" in str(err)
    assert "data CRC32C mismatch" in str(err)


def test_corrupt_length_field(tmp_path: Path) -> None:
    path = tmp_path / "len.tfrecord"
    _write_tfrecord(path, [b"payload"])
    raw = bytearray(path.read_bytes())
    raw[0] ^= 0x40
    path.write_bytes(bytes(raw))
    with pytest.raises(CorruptLogError, match="record 0.*length CRC32C mismatch"):
        list(iter_tfrecords(path))


@pytest.mark.parametrize("keep", [5, 12 + 3, 12 + 7 + 2])
def test_truncated_synthetic_record(tmp_path: Path, keep: int) -> None:
    path = tmp_path / "cut.tfrecord"
    _write_tfrecord(path, [b"payload"])
    path.write_bytes(path.read_bytes()[:keep])
    with pytest.raises(CorruptLogError, match="record 0.*truncated"):
        list(iter_tfrecords(path))


@pytest.mark.shared_data
def test_flipped_byte_in_waymo_sample(shared_data: Path, tmp_path: Path) -> None:
    copy = tmp_path / "flipped.tfrecord"
    raw = bytearray((shared_data / WAYMO_FRAME).read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    copy.write_bytes(bytes(raw))
    with pytest.raises(CorruptLogError) as info:
        load_waymo_frames(copy)
    assert info.value.record_index == 0
    assert "record 0" in str(info.value) and str(copy) in str(info.value)
    assert isinstance(info.value, ValueError)


@pytest.mark.shared_data
def test_truncated_waymo_sample(shared_data: Path, tmp_path: Path) -> None:
    copy = tmp_path / "cut.tfrecord"
    shutil.copyfile(shared_data / WAYMO_FRAME, copy)
    with copy.open("r+b") as fh:
        fh.truncate(copy.stat().st_size - 1000)
    with pytest.raises(CorruptLogError, match=r"record 0 \(byte offset 0\).*truncated"):
        load_waymo_frames(copy)


@pytest.mark.shared_data
def test_waymo_sample_crc_is_valid(shared_data: Path) -> None:
    records = list(iter_tfrecords(shared_data / WAYMO_FRAME))
    assert len(records) == 1
    assert len(records[0].data) == (shared_data / WAYMO_FRAME).stat().st_size - 16
