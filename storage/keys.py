"""Content keys: a stable SHA-256 over the inputs and config of a stage.

``content_key(*parts)`` hashes a canonical JSON encoding of its arguments, so the key is the same
across processes, machines and Python versions for equal inputs, and differs when any input differs.

Canonical encoding:

* ``None``, ``bool``, ``int``, ``float`` (repr, exact), ``str``: as JSON (``1`` and ``1.0`` differ);
* ``list``/``tuple``: JSON arrays; ``set``/``frozenset``: sorted by encoding;
* ``dict``: JSON objects with sorted ``str`` keys (other key types raise ``TypeError``);
* dataclasses: their class name plus fields (not ``asdict``, so arrays are not copied); a field whose
  metadata sets ``KEY_OMIT_WHEN_NONE`` is left out while ``None``;
* ``numpy`` arrays: dtype, shape and a SHA-256 of the C-contiguous bytes; numpy scalars: ``.item()``;
* ``bytes``: SHA-256; ``pathlib`` paths and enums: their string / value.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
import pathlib
from typing import Any

import numpy as np

from simsplat_core.types import KEY_OMIT_WHEN_NONE

KEY_VERSION = "simsplat-key-v1"



def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def canonical(value: Any) -> Any:
    """JSON-serialisable canonical form of ``value`` (see module docstring)."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, enum.Enum):
        return {"__enum__": type(value).__qualname__, "value": canonical(value.value)}
    if isinstance(value, np.ndarray):
        if value.dtype == object:
            raise TypeError("content_key: object arrays are not supported")
        data = np.ascontiguousarray(value).tobytes()
        return {"__ndarray__": value.dtype.str, "shape": list(value.shape), "sha256": _digest(data)}
    if isinstance(value, np.generic):
        return canonical(value.item())
    if isinstance(value, (bytes, bytearray, memoryview)):
        return {"__bytes__": _digest(bytes(value))}
    if isinstance(value, pathlib.PurePath):
        return {"__path__": value.as_posix()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {
            f.name: canonical(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if not (f.metadata.get(KEY_OMIT_WHEN_NONE) and getattr(value, f.name) is None)
        }
        return {"__dataclass__": type(value).__qualname__, "fields": fields}
    if isinstance(value, dict):
        bad = [k for k in value if not isinstance(k, str)]
        if bad:
            raise TypeError(f"content_key: dict keys must be str, got {type(bad[0]).__name__} {bad[0]!r}")
        return {k: canonical(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [canonical(v) for v in value]
    if isinstance(value, (set, frozenset)):
        return {"__set__": sorted((canonical(v) for v in value), key=_encode)}
    raise TypeError(f"content_key: cannot hash a {type(value).__name__}")


def _encode(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=True)


def content_key(*parts: Any) -> str:
    """64-hex-digit SHA-256 of the canonical encoding of ``parts``."""
    payload = _encode([KEY_VERSION, [canonical(p) for p in parts]])
    return _digest(payload.encode("utf-8"))


def config_settings(config: Any, exclude: tuple[str, ...] = ()) -> dict[str, Any]:
    """A dataclass config as the dict a content key hashes, less fields that never change the output
    (``exclude``: core counts, progress intervals, ...)."""
    return {k: v for k, v in dataclasses.asdict(config).items() if k not in exclude}
