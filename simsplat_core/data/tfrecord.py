"""Lazy, checksum-verifying TFRecord reader.

Framing of every record (all little-endian)::

    uint64 length
    uint32 masked_crc32c(length bytes)
    byte   data[length]
    uint32 masked_crc32c(data)

Both checksums are verified; a short read or a mismatch raises ``CorruptLogError`` naming the file,
the record index and the byte offset of the record. Nothing is returned for a record before its
data checksum has been verified, so a damaged file never yields a silent partial result.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from simsplat_core.data.crc32c import masked_crc32c
from simsplat_core.data.errors import CorruptLogError

logger = logging.getLogger(__name__)

_HEADER = struct.Struct("<QI")
_FOOTER = struct.Struct("<I")


@dataclass(frozen=True)
class TFRecord:
    """One verified record.

    Attributes:
        index: zero-based record index in the file.
        offset: byte offset of the record's length field in the file.
        data: the record payload (a serialized proto for Waymo files).
    """

    index: int
    offset: int
    data: bytes


def iter_tfrecords(path: str | Path) -> Iterator[TFRecord]:
    """Yield the records of a TFRecord file one at a time, verifying both CRCs of each.

    Raises:
        CorruptLogError: truncated header/data/footer, or a length / data CRC mismatch.
        FileNotFoundError: ``path`` does not exist.
    """
    path = Path(path)
    file_size = path.stat().st_size
    with path.open("rb") as fh:
        index = 0
        offset = 0
        while True:
            header = fh.read(_HEADER.size)
            if not header:
                return
            where = f"record {index} (byte offset {offset})"

            def fail(reason: str) -> CorruptLogError:
                return CorruptLogError(path, where, reason, record_index=index, offset=offset)  # noqa: B023

            if len(header) < _HEADER.size:
                raise fail(f"truncated record header: {len(header)} of {_HEADER.size} bytes")
            length, length_crc = _HEADER.unpack(header)
            if masked_crc32c(header[:8]) != length_crc:
                raise fail("length CRC32C mismatch (corrupt length field)")
            remaining = file_size - offset - _HEADER.size
            if length + _FOOTER.size > remaining:
                raise fail(f"truncated record: needs {length + _FOOTER.size} bytes, {remaining} left in file")
            data = fh.read(length)
            footer = fh.read(_FOOTER.size)
            if len(data) < length or len(footer) < _FOOTER.size:
                raise fail("truncated record data (file changed while reading?)")
            (data_crc,) = _FOOTER.unpack(footer)
            if masked_crc32c(data) != data_crc:
                raise fail(f"data CRC32C mismatch over {length} bytes")
            yield TFRecord(index=index, offset=offset, data=data)
            offset += _HEADER.size + length + _FOOTER.size
            index += 1


def encode_tfrecord(data: bytes) -> bytes:
    """Frame one payload as a TFRecord record (header + data + footer); inverse of ``iter_tfrecords``."""
    length = struct.pack("<Q", len(data))
    return length + struct.pack("<I", masked_crc32c(length)) + data + struct.pack("<I", masked_crc32c(data))
