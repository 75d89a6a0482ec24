"""Protobuf wire-format decoder: hand-encoded bytes, malformed input, and a cross-check with protobuf."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from simsplat_core.data.protowire import EnumSchema, Field, MessageSchema, ProtoDecodeError, decode_message

INNER = MessageSchema("Inner", (Field(1, "x", "double"), Field(2, "tags", "string", repeated=True)))
OUTER = MessageSchema(
    "Outer",
    (
        Field(1, "name", "string"),
        Field(2, "count", "int32"),
        Field(3, "values", "double", repeated=True),
        Field(4, "inner", "message", message=INNER),
        Field(5, "items", "message", repeated=True, message=INNER),
        Field(6, "flag", "bool"),
        Field(7, "ratio", "float"),
        Field(8, "ids", "int64", repeated=True),
        Field(9, "blob", "bytes"),
    ),
)


def varint(value: int) -> bytes:
    value &= (1 << 64) - 1
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def tag(number: int, wire: int) -> bytes:
    return varint(number << 3 | wire)


def ld(number: int, payload: bytes) -> bytes:
    return tag(number, 2) + varint(len(payload)) + payload


def test_scalars_nested_and_repeated() -> None:
    inner = tag(1, 1) + struct.pack("<d", 2.5) + ld(2, b"a") + ld(2, b"b")
    msg = (
        ld(1, "Zoë".encode())
        + tag(2, 0)
        + varint(-7)
        + tag(3, 1)
        + struct.pack("<d", 1.0)  # unpacked element
        + ld(3, struct.pack("<2d", 2.0, 3.0))  # then a packed run
        + ld(4, inner)
        + ld(5, inner)
        + ld(5, b"")
        + tag(6, 0)
        + varint(1)
        + tag(7, 5)
        + struct.pack("<f", 0.5)
        + ld(8, varint(1) + varint(300) + varint(-1))
        + ld(9, b"\x00\xff")
        + tag(99, 0)
        + varint(5)
        + tag(98, 1)
        + bytes(8)
        + tag(97, 5)
        + bytes(4)
        + ld(96, b"skip me")
    )
    out = decode_message(msg, OUTER)
    assert out["name"] == "Zoë" and out["count"] == -7 and out["flag"] is True and out["ratio"] == 0.5
    np.testing.assert_array_equal(out["values"], [1.0, 2.0, 3.0])
    assert out["values"].dtype == np.float64
    assert out["inner"] == {"x": 2.5, "tags": ["a", "b"]}
    assert out["items"] == [{"x": 2.5, "tags": ["a", "b"]}, {"x": None, "tags": []}]
    assert out["ids"] == [1, 300, -1]
    assert out["blob"] == b"\x00\xff"


def test_absent_fields_have_defaults() -> None:
    out = decode_message(b"", OUTER)
    assert out["name"] is None and out["inner"] is None and out["items"] == [] and out["values"].shape == (0,)


@pytest.mark.parametrize(
    ("data", "path", "reason"),
    [
        (tag(2, 0) + b"\x80\x80", "Outer.count", "truncated varint"),
        (ld(1, b"abc")[:-1], "Outer.name", "runs past the end"),
        (tag(1, 0) + varint(3), "Outer.name", "does not match string"),
        (tag(3, 3), "Outer.values", "unsupported wire type 3"),
        (ld(1, b"\xff\xfe"), "Outer.name", "invalid UTF-8"),
        (ld(3, b"\x00" * 7), "Outer.values", "not a multiple of 8"),
        (ld(5, tag(1, 1) + b"\x00\x00"), "Outer.items[0].x", "truncated 64-bit"),
        (tag(2, 0) + b"\xff" * 11, "Outer.count", "longer than 10 bytes"),
        (b"\x00", "Outer", "field number 0"),
    ],
)
def test_malformed_input_names_the_field(data: bytes, path: str, reason: str) -> None:
    with pytest.raises(ProtoDecodeError, match=reason) as info:
        decode_message(data, OUTER)
    assert info.value.field_path == path


def test_agrees_with_protobuf_library() -> None:
    """Encode with the official protobuf runtime (packed and unpacked), decode with ours."""
    descriptor_pb2 = pytest.importorskip("google.protobuf.descriptor_pb2")
    from google.protobuf import descriptor_pool, message_factory

    fdp = descriptor_pb2.FileDescriptorProto(name="wiretest.proto", package="wiretest", syntax="proto2")
    inner = fdp.message_type.add(name="Inner")
    inner.field.add(name="x", number=1, type=descriptor_pb2.FieldDescriptorProto.TYPE_DOUBLE, label=1)
    inner.field.add(name="tags", number=2, type=descriptor_pb2.FieldDescriptorProto.TYPE_STRING, label=3)
    outer = fdp.message_type.add(name="Outer")
    t = descriptor_pb2.FieldDescriptorProto
    outer.field.add(name="name", number=1, type=t.TYPE_STRING, label=1)
    outer.field.add(name="count", number=2, type=t.TYPE_INT32, label=1)
    outer.field.add(name="values", number=3, type=t.TYPE_DOUBLE, label=3)  # proto2: unpacked
    outer.field.add(name="inner", number=4, type=t.TYPE_MESSAGE, type_name=".wiretest.Inner", label=1)
    outer.field.add(name="items", number=5, type=t.TYPE_MESSAGE, type_name=".wiretest.Inner", label=3)
    outer.field.add(name="flag", number=6, type=t.TYPE_BOOL, label=1)
    outer.field.add(name="ratio", number=7, type=t.TYPE_FLOAT, label=1)
    packed = outer.field.add(name="ids", number=8, type=t.TYPE_INT64, label=3)
    packed.options.packed = True
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fdp)
    cls = message_factory.GetMessageClass(pool.FindMessageTypeByName("wiretest.Outer"))
    msg = cls(name="segment", count=-123456, values=[0.1, -2.0, 1e300], flag=True, ratio=0.25, ids=[0, -5, 2**40])
    msg.inner.x = -1.5
    msg.inner.tags.extend(["u", "v"])
    msg.items.add(x=3.0)
    out = decode_message(msg.SerializeToString(), OUTER)
    assert out["name"] == "segment" and out["count"] == -123456 and out["flag"] is True and out["ratio"] == 0.25
    np.testing.assert_array_equal(out["values"], [0.1, -2.0, 1e300])
    assert out["ids"] == [0, -5, 2**40]
    assert out["inner"] == {"x": -1.5, "tags": ["u", "v"]}
    assert out["items"] == [{"x": 3.0, "tags": []}]


def test_enum_schema_and_field_definitions() -> None:
    colour = EnumSchema("Colour", ("RED", "GREEN"))
    assert colour.number("GREEN") == 1 and colour.name_of(0) == "RED" and colour.name_of(7) == "7"
    with pytest.raises(ValueError, match="'BLUE' is not a Colour value"):
        colour.number("BLUE")
    with pytest.raises(ValueError, match="'size': an enum type is only for enum fields"):
        Field(1, "size", "int32", enum=colour)
    with pytest.raises(ValueError, match="'ids': only repeated numeric fields can be packed"):
        Field(1, "ids", "int64", packed=True)
    # Definition-only attributes do not change decoding.
    fields = (Field(1, "c", "enum", enum=colour), Field(2, "ids", "int64", repeated=True, packed=True))
    schema = MessageSchema("M", fields)
    assert decode_message(b"\x08\x01\x12\x02\x03\x04", schema) == {"c": 1, "ids": [3, 4]}
