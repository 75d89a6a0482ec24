"""Protobuf runtime message classes built from ``protowire`` schemas, so a format is defined once for reading and
writing.

``file_descriptor`` turns the message schemas reachable from some root schemas into a proto2
``FileDescriptorProto`` (field numbers, scalar and enum types, repeated / packed, ``oneof`` groups; each enum
nested in the message that declares it in ``MessageSchema.enums``, top level otherwise). ``message_classes``
loads it into a private ``DescriptorPool`` (nothing is registered in protobuf's default pool) and returns the
generated classes by message name. The schemas must name every field a writer sets and give every enum field its
``EnumSchema``.

``fixed_width_records`` writes many occurrences of a repeated message field whose set fields all have a fixed
width (``double``, ``float``, ``fixed32/64``, ``bool``) with numpy, for a writer to hand to the runtime's
``MergeFromString`` in one call instead of setting thousands of small messages field by field from Python (a
91-step, 100-agent ``Scenario`` holds 9,100 ``ObjectState`` s). The runtime parses and checks those bytes, and
serializes the final message itself.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from simsplat_core.data.protowire import WIRE_I32, WIRE_I64, WIRE_LEN, WIRE_VARINT, EnumSchema, Field, MessageSchema

_FDP = descriptor_pb2.FieldDescriptorProto
_TYPE_OF_KIND: dict[str, int] = {
    "double": _FDP.TYPE_DOUBLE,
    "float": _FDP.TYPE_FLOAT,
    "int32": _FDP.TYPE_INT32,
    "int64": _FDP.TYPE_INT64,
    "uint32": _FDP.TYPE_UINT32,
    "uint64": _FDP.TYPE_UINT64,
    "bool": _FDP.TYPE_BOOL,
    "enum": _FDP.TYPE_ENUM,
    "fixed32": _FDP.TYPE_FIXED32,
    "fixed64": _FDP.TYPE_FIXED64,
    "string": _FDP.TYPE_STRING,
    "bytes": _FDP.TYPE_BYTES,
    "message": _FDP.TYPE_MESSAGE,
}


def reachable_schemas(roots: Sequence[MessageSchema]) -> dict[str, MessageSchema]:
    """Every message schema reachable from ``roots`` through message fields, by name, roots first.

    Raises:
        ValueError: two different schemas share a name.
    """
    found: dict[str, MessageSchema] = {}
    stack = list(reversed(roots))
    while stack:
        schema = stack.pop()
        known = found.get(schema.name)
        if known is not None:
            if known != schema:
                raise ValueError(f"two different message schemas are named {schema.name!r}")
            continue
        found[schema.name] = schema
        stack.extend(f.message for f in reversed(schema.fields) if f.message is not None)
    return found


def _enum_proto(enum: EnumSchema) -> descriptor_pb2.EnumDescriptorProto:
    out = descriptor_pb2.EnumDescriptorProto(name=enum.name)
    for number, value_name in enumerate(enum.values):
        out.value.add(name=value_name, number=number)
    return out


def _field_proto(fld: Field, scope_of: dict[str, str], owner: str) -> descriptor_pb2.FieldDescriptorProto:
    label = _FDP.LABEL_REPEATED if fld.repeated else _FDP.LABEL_OPTIONAL
    out = descriptor_pb2.FieldDescriptorProto(name=fld.name, number=fld.number, label=label,
                                              type=_TYPE_OF_KIND[fld.kind])
    if fld.message is not None:
        out.type_name = f"{scope_of['']}.{fld.message.name}"
    if fld.kind == "enum":
        if fld.enum is None:
            raise ValueError(f"{owner}.{fld.name}: an enum field needs its EnumSchema to build a message class")
        out.type_name = f"{scope_of.get(fld.enum.name, scope_of[''])}.{fld.enum.name}"
    if fld.packed:
        out.options.packed = True
    return out


def file_descriptor(file_name: str, package: str, roots: Sequence[MessageSchema]) -> descriptor_pb2.FileDescriptorProto:
    """A proto2 file holding the messages reachable from ``roots`` (module docstring).

    Raises:
        ValueError: two different schemas or enums share a name, or an enum field has no ``EnumSchema``.
    """
    schemas = reachable_schemas(roots)
    scope_of = {"": f".{package}"}  # enum name -> the full name of its scope ("" -> the package)
    declared: dict[str, EnumSchema] = {}
    for schema in schemas.values():
        for enum in schema.enums:
            if declared.setdefault(enum.name, enum) != enum:
                raise ValueError(f"two different enum schemas are named {enum.name!r}")
            scope_of[enum.name] = f".{package}.{schema.name}"
    top_level = {f.enum.name: f.enum for s in schemas.values() for f in s.fields
                 if f.enum is not None and f.enum.name not in declared}
    out = descriptor_pb2.FileDescriptorProto(name=file_name, package=package, syntax="proto2")
    out.enum_type.extend(_enum_proto(e) for e in top_level.values())
    for schema in schemas.values():
        msg = out.message_type.add(name=schema.name)
        msg.enum_type.extend(_enum_proto(e) for e in schema.enums)
        oneofs: list[str] = []
        for fld in schema.fields:
            field_proto = _field_proto(fld, scope_of, schema.name)
            if fld.oneof:
                if fld.oneof not in oneofs:
                    oneofs.append(fld.oneof)
                    msg.oneof_decl.add(name=fld.oneof)
                field_proto.oneof_index = oneofs.index(fld.oneof)
            msg.field.append(field_proto)
    return out


def message_classes(file_name: str, package: str, roots: Sequence[MessageSchema]) -> dict[str, Any]:
    """Message name -> generated protobuf class, for every message reachable from ``roots`` (module docstring)."""
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file_descriptor(file_name, package, roots))
    return {
        name: message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{package}.{name}"))
        for name in reachable_schemas(roots)
    }


def field_named(schema: MessageSchema, name: str) -> Field:
    """The field ``name`` of ``schema``; ``KeyError`` naming the message when it has none."""
    for fld in schema.fields:
        if fld.name == name:
            return fld
    raise KeyError(f"message {schema.name} has no field {name!r}")


def _varint(value: int) -> bytes:
    out = bytearray()
    while True:
        byte, value = value & 0x7F, value >> 7
        out.append(byte | (0x80 if value else 0))
        if not value:
            return bytes(out)


#: Fixed-width field kinds -> (wire type, little-endian numpy dtype of the value).
_FIXED_WIDTH: dict[str, tuple[int, str]] = {
    "double": (WIRE_I64, "<f8"),
    "fixed64": (WIRE_I64, "<u8"),
    "float": (WIRE_I32, "<f4"),
    "fixed32": (WIRE_I32, "<u4"),
    "bool": (WIRE_VARINT, "u1"),  # 0 / 1: a one-byte varint
}


def _record_layout(field: Field, columns: Sequence[str]) -> tuple[np.dtype, dict[str, bytes]]:
    """The numpy record of one occurrence of ``field`` with ``columns`` set: a structured dtype of constant parts
    (``head``: tag and length of ``field``; ``tag<k>``: tag of column ``k``) and values (``value<k>``), and the
    constant parts' bytes."""
    assert field.message is not None
    constants: dict[str, bytes] = {}
    parts: list[tuple[str, str]] = []  # (name, numpy format), in wire order
    for k, name in enumerate(columns):
        sub = field_named(field.message, name)
        if sub.repeated or sub.kind not in _FIXED_WIDTH:
            raise ValueError(f"{field.message.name}.{name}: not a singular fixed-width field ({sub.kind})")
        wire, dtype = _FIXED_WIDTH[sub.kind]
        constants[f"tag{k}"] = _varint(sub.number << 3 | wire)
        parts += [(f"tag{k}", f"V{len(constants[f'tag{k}'])}"), (f"value{k}", dtype)]
    size = sum(np.dtype(fmt).itemsize for _, fmt in parts)
    constants["head"] = _varint(field.number << 3 | WIRE_LEN) + _varint(size)
    parts.insert(0, ("head", f"V{len(constants['head'])}"))
    record = np.dtype([(name, fmt) for name, fmt in parts])  # packed: no alignment padding
    return record, constants


def fixed_width_records(field: Field, columns: Sequence[str], values: np.ndarray) -> np.ndarray:
    """``[N, R]`` uint8: row ``n`` is one occurrence of the repeated message field ``field`` (its tag, the message's
    length and the message) whose fields ``columns`` hold ``values[n]``, in the order given.

    Args:
        field: a repeated ``message`` field (e.g. ``Track.states``).
        columns: names of fields of its message, each of a fixed-width kind (``_FIXED_WIDTH``).
        values: ``[N, len(columns)]`` numbers; cast to each field's type as the runtime would (``float`` rounds to
            nearest float32, ``bool`` is ``value != 0``).

    Raises:
        ValueError: ``field`` is not a repeated message field, a column is not a fixed-width field of its message,
            or ``values`` has the wrong shape.
    """
    if field.kind != "message" or not field.repeated or field.message is None:
        raise ValueError(f"field {field.name!r}: fixed-width records are for repeated message fields")
    values = np.asarray(values)
    if values.ndim != 2 or values.shape[1] != len(columns):
        raise ValueError(f"field {field.name!r}: values must be [N, {len(columns)}], got {list(values.shape)}")
    record, constants = _record_layout(field, columns)
    out = np.empty(len(values), record)
    for name, data in constants.items():
        out[name] = np.void(data)
    for k, name in enumerate(columns):
        column = values[:, k]
        out[f"value{k}"] = column != 0 if field_named(field.message, name).kind == "bool" else column
    return out.view(np.uint8).reshape(len(values), record.itemsize)
