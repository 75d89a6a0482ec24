"""The one error every driving-log loader raises for a damaged or malformed input file."""

from __future__ import annotations

from pathlib import Path


class CorruptLogError(ValueError):
    """A log file is truncated, fails a checksum, or lacks / mangles a required column or field.

    The message always names the file and the place inside it (record index and byte offset for
    TFRecords, column for feather tables, field path for protos and JSON), so the error alone is
    enough to find the bad bytes.

    Attributes:
        path: the offending file (or log directory).
        where: human-readable place inside the file, e.g. ``"record 3 (byte offset 1024)"``,
            ``"column 'tx_m'"``, ``"field 'Frame.images[2].image'"``.
        reason: what is wrong there.
        record_index: TFRecord record index, when known.
        offset: byte offset inside the file, when known.
    """

    def __init__(
        self,
        path: str | Path,
        where: str,
        reason: str,
        *,
        record_index: int | None = None,
        offset: int | None = None,
    ) -> None:
        self.path = str(path)
        self.where = where
        self.reason = reason
        self.record_index = record_index
        self.offset = offset
        super().__init__(f"{self.path}: {where}: {reason}")
