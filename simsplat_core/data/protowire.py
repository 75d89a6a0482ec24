"""A small schema-driven decoder for the protobuf wire format.

Only what reading public ``.proto`` files by field number needs: varint (0), 64-bit (1),
length-delimited (2) and 32-bit (5) wire types, packed and unpacked repeated scalars, nested
messages, strings and bytes. Unknown fields are skipped; group wire types (3, 4) are rejected.

A message is described by a ``MessageSchema`` (a tuple of ``Field`` s) and decoded into a plain
``dict`` keyed by field name:

* singular scalars -> ``int`` / ``float`` / ``bool`` / ``str`` / ``bytes``, or ``None`` when absent
  (the last occurrence wins, as in protobuf);
* repeated ``double`` / ``float`` -> ``[n]`` float64 ``np.ndarray``; other repeated scalars -> ``list``;
* messages -> ``dict`` (singular, ``None`` when absent) or ``list[dict]`` (repeated).

Every malformed input raises ``ProtoDecodeError`` with the dotted field path (e.g.
``Frame.images[2].pose.transform``) and the byte offset inside the decoded buffer.

A schema may also carry what the wire format does not need but a full message definition does (enum types and
their value names, ``[packed = true]``, ``oneof`` groups), so that one schema can both decode here and define
protobuf runtime classes for writing (``simsplat_core.export.schema_messages``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

WIRE_VARINT = 0
WIRE_I64 = 1
WIRE_LEN = 2
WIRE_I32 = 5

_VARINT_KINDS = frozenset({"int32", "int64", "uint32", "uint64", "bool", "enum"})
_WIRE_OF_KIND = {
    **{kind: WIRE_VARINT for kind in _VARINT_KINDS},
    "double": WIRE_I64,
    "fixed64": WIRE_I64,
    "float": WIRE_I32,
    "fixed32": WIRE_I32,
    "string": WIRE_LEN,
    "bytes": WIRE_LEN,
    "message": WIRE_LEN,
}
_NUMPY_OF_KIND = {"double": "<f8", "float": "<f4", "fixed64": "<u8", "fixed32": "<u4"}


class ProtoDecodeError(ValueError):
    """Malformed protobuf bytes. ``field_path`` names the field, ``offset`` the byte position (-1: unknown)."""

    def __init__(self, field_path: str, offset: int, reason: str) -> None:
        self.field_path = field_path
        self.offset = offset
        self.reason = reason
        at = f" at byte {offset}" if offset >= 0 else ""
        super().__init__(f"field {field_path!r}{at}: {reason}")


@dataclass(frozen=True)
class EnumSchema:
    """An enum type: its name and its value names in value order (a value is its index)."""

    name: str
    values: tuple[str, ...]

    def number(self, value_name: str) -> int:
        """The enum value of ``value_name``; ``ValueError`` naming the enum when it is not one of its values."""
        try:
            return self.values.index(value_name)
        except ValueError:
            raise ValueError(f"{value_name!r} is not a {self.name} value {list(self.values)}") from None

    def name_of(self, number: int) -> str:
        """The value name of ``number``, or the number as text when the enum has no such value."""
        return self.values[number] if 0 <= number < len(self.values) else str(number)


@dataclass(frozen=True)
class Field:
    """One field of a message schema.

    Attributes:
        number: protobuf field number.
        name: key in the decoded dict.
        kind: ``double``, ``float``, ``int32``, ``int64``, ``uint32``, ``uint64``, ``bool``, ``enum``,
            ``fixed32``, ``fixed64``, ``string``, ``bytes`` or ``message``.
        repeated: whether the field is ``repeated``.
        message: schema of the nested message when ``kind == "message"``.
        enum: the enum type of an ``enum`` field (optional for decoding, required to build a runtime class).
        packed: a repeated scalar written packed (``[packed = true]``); decoding accepts both encodings.
        oneof: the name of the ``oneof`` group the field belongs to, ``""`` for none.
    """

    number: int
    name: str
    kind: str
    repeated: bool = False
    message: MessageSchema | None = None
    enum: EnumSchema | None = None
    packed: bool = False
    oneof: str = ""

    def __post_init__(self) -> None:
        if self.kind not in _WIRE_OF_KIND:
            raise ValueError(f"field {self.name!r}: unknown kind {self.kind!r}")
        if (self.kind == "message") != (self.message is not None):
            raise ValueError(f"field {self.name!r}: a schema is required exactly for message fields")
        if self.enum is not None and self.kind != "enum":
            raise ValueError(f"field {self.name!r}: an enum type is only for enum fields")
        if self.packed and not (self.repeated and _WIRE_OF_KIND[self.kind] != WIRE_LEN):
            raise ValueError(f"field {self.name!r}: only repeated numeric fields can be packed")


@dataclass(frozen=True)
class MessageSchema:
    """A message type: its name (for error paths), the subset of its fields to decode and the enum types it
    declares (nested in it when a runtime class is built; decoding does not need them)."""

    name: str
    fields: tuple[Field, ...]
    enums: tuple[EnumSchema, ...] = ()
    by_number: dict[int, Field] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        by_number = {f.number: f for f in self.fields}
        if len(by_number) != len(self.fields):
            raise ValueError(f"message {self.name}: duplicate field numbers")
        object.__setattr__(self, "by_number", by_number)


def read_varint(buf: bytes, pos: int, end: int, path: str) -> tuple[int, int]:
    """Decode one base-128 varint at ``buf[pos]``; returns ``(value, next_pos)`` (value < 2**64)."""
    result = 0
    shift = 0
    start = pos
    while True:
        if pos >= end:
            raise ProtoDecodeError(path, start, "truncated varint")
        byte = buf[pos]
        pos += 1
        result |= (byte & 0x7F) << shift
        if byte < 0x80:
            if result >> 64:
                raise ProtoDecodeError(path, start, "varint exceeds 64 bits")
            return result, pos
        shift += 7
        if shift >= 70:
            raise ProtoDecodeError(path, start, "varint longer than 10 bytes")


def _convert_varint(kind: str, value: int) -> int | bool:
    if kind == "bool":
        return value != 0
    if kind in ("int32", "int64", "enum") and value >= 1 << 63:
        return value - (1 << 64)  # two's-complement negative
    if kind == "uint32":
        return value & 0xFFFFFFFF
    return value


def _scalar_fixed(kind: str, buf: bytes, pos: int) -> float | int:
    return np.frombuffer(buf, dtype=_NUMPY_OF_KIND[kind], count=1, offset=pos)[0].item()


def _decode_packed(fld: Field, buf: bytes, pos: int, end: int, path: str) -> list[Any] | np.ndarray:
    if fld.kind in _VARINT_KINDS:
        values = []
        while pos < end:
            value, pos = read_varint(buf, pos, end, path)
            values.append(_convert_varint(fld.kind, value))
        return values
    dtype = np.dtype(_NUMPY_OF_KIND[fld.kind])
    if (end - pos) % dtype.itemsize:
        raise ProtoDecodeError(
            path, pos, f"packed {fld.kind} payload of {end - pos} bytes is not a multiple of {dtype.itemsize}"
        )
    return np.frombuffer(buf, dtype=dtype, count=(end - pos) // dtype.itemsize, offset=pos)


def decode_message(  # noqa: C901, PLR0915 -- the protobuf wire-format grammar: one branch per wire type and field kind, in one read loop
    buf: bytes, schema: MessageSchema, start: int = 0, end: int | None = None, path: str | None = None
) -> dict[str, Any]:
    """Decode ``buf[start:end]`` as one message of ``schema`` (see module docstring for the result).

    Raises:
        ProtoDecodeError: truncated data, wire type not matching the schema, invalid tag, bad UTF-8.
    """
    end = len(buf) if end is None else end
    path = schema.name if path is None else path
    out: dict[str, Any] = {}
    repeated_parts: dict[str, list[Any]] = {}
    for field_def in schema.fields:
        if field_def.repeated:
            repeated_parts[field_def.name] = []
        else:
            out[field_def.name] = None
    pos = start
    while pos < end:
        tag_pos = pos
        tag, pos = read_varint(buf, pos, end, path)
        number, wire = tag >> 3, tag & 7
        if number == 0:
            raise ProtoDecodeError(path, tag_pos, "invalid field number 0")
        fld = schema.by_number.get(number)
        fpath = f"{path}.{fld.name}" if fld is not None else f"{path}.<field {number}>"
        # Locate the payload [p0, p1) of this field.
        if wire == WIRE_VARINT:
            value, pos = read_varint(buf, pos, end, fpath)
            p0 = p1 = -1
        elif wire in (WIRE_I64, WIRE_I32):
            size = 8 if wire == WIRE_I64 else 4
            if pos + size > end:
                raise ProtoDecodeError(fpath, pos, f"truncated {size * 8}-bit value")
            p0, p1 = pos, pos + size
            pos = p1
        elif wire == WIRE_LEN:
            length, pos = read_varint(buf, pos, end, fpath)
            if pos + length > end:
                raise ProtoDecodeError(
                    fpath, pos, f"length {length} runs past the end of the message ({end - pos} bytes left)"
                )
            p0, p1 = pos, pos + length
            pos = p1
        else:
            raise ProtoDecodeError(fpath, tag_pos, f"unsupported wire type {wire}")
        if fld is None:
            continue
        expected = _WIRE_OF_KIND[fld.kind]
        if wire == expected:
            if wire == WIRE_VARINT:
                item: Any = _convert_varint(fld.kind, value)
            elif wire in (WIRE_I64, WIRE_I32):
                item = _scalar_fixed(fld.kind, buf, p0)
            elif fld.kind == "message":
                assert fld.message is not None
                index = len(repeated_parts[fld.name]) if fld.repeated else None
                sub_path = f"{fpath}[{index}]" if index is not None else fpath
                item = decode_message(buf, fld.message, p0, p1, sub_path)
            elif fld.kind == "string":
                try:
                    item = bytes(buf[p0:p1]).decode("utf-8")
                except UnicodeDecodeError as exc:
                    raise ProtoDecodeError(fpath, p0, f"invalid UTF-8 string: {exc.reason}") from exc
            else:
                item = bytes(buf[p0:p1])
            if fld.repeated:
                repeated_parts[fld.name].append(item)
            else:
                out[fld.name] = item
        elif wire == WIRE_LEN and fld.repeated and expected != WIRE_LEN:
            repeated_parts[fld.name].append(_decode_packed(fld, buf, p0, p1, fpath))
        else:
            raise ProtoDecodeError(fpath, tag_pos, f"wire type {wire} does not match {fld.kind} (expected {expected})")
    for fld in schema.fields:
        if not fld.repeated:
            continue
        parts = repeated_parts[fld.name]
        if fld.kind in _NUMPY_OF_KIND:
            dtype = np.float64 if fld.kind in ("double", "float") else np.uint64
            arrays = [np.atleast_1d(np.asarray(p)).astype(dtype) for p in parts]
            out[fld.name] = np.concatenate(arrays) if arrays else np.zeros(0, dtype=dtype)
        else:
            flat: list[Any] = []
            for p in parts:
                if isinstance(p, list) and fld.kind in _VARINT_KINDS:
                    flat.extend(p)
                else:
                    flat.append(p)
            out[fld.name] = flat
    return out
