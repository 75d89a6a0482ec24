"""Exceptions raised by the storage layer.

Every message names the artifact (its URI) so that a failure in a fan-out run points at one file.
"""

from __future__ import annotations


class StorageError(Exception):
    """Base class of every storage-layer error."""


class UnsafePathError(StorageError, ValueError):
    """A relative artifact path is absolute, contains ``..`` or is otherwise outside the store root."""


class SchemaError(StorageError, ValueError):
    """A table does not match its declared schema; the message names the file and the column."""


class CorruptArtifactError(StorageError, ValueError):
    """A file exists but cannot be decoded (truncated Parquet, broken EXR, invalid JSON)."""


class StoreNotWritableError(StorageError, OSError):
    """The store cannot be written: the disk is full, the filesystem is read-only, permission is denied, or the root
    is not a directory. The message names the file, the store root and which of these it is."""


class MissingInputError(StorageError, FileNotFoundError, ValueError):
    """A stage's input is not in the store; the message names what is missing and the command that makes it.

    A ``FileNotFoundError`` (the artifact is not there) and a ``ValueError`` (the sequences asked for cannot be
    used): callers that catch either catch it."""
