"""Runtime message classes built from ``protowire`` schemas, and the numpy-laid repeated records."""

from __future__ import annotations

import numpy as np
import pytest
from google.protobuf import descriptor

from simsplat_core.data.protowire import EnumSchema, Field, MessageSchema
from simsplat_core.data.waymo_scenario_proto import SCENARIO, TRACK
from simsplat_core.export import womd_messages
from simsplat_core.export.record import STATE_COLUMNS
from simsplat_core.export.schema_messages import field_named, file_descriptor, fixed_width_records, message_classes

COLOUR = EnumSchema("Colour", ("RED", "GREEN"))
POINT = MessageSchema("Point", (Field(1, "x", "double"), Field(2, "y", "float"), Field(20, "ok", "bool")))
SHAPE = MessageSchema(
    "Shape",
    (
        Field(1, "points", "message", repeated=True, message=POINT),
        Field(2, "colour", "enum", enum=COLOUR),
        Field(3, "ids", "int64", repeated=True, packed=True),
        Field(4, "circle", "message", message=POINT, oneof="form"),
        Field(5, "label", "string", oneof="form"),
    ),
    enums=(COLOUR,),
)


def test_file_descriptor_nests_enums_and_keeps_numbers_packing_and_oneofs() -> None:
    classes = message_classes("test/shape.proto", "test.pkg", (SHAPE,))
    assert set(classes) == {"Shape", "Point"}
    shape = classes["Shape"].DESCRIPTOR
    assert shape.full_name == "test.pkg.Shape"
    assert shape.enum_types_by_name["Colour"].full_name == "test.pkg.Shape.Colour"
    assert {f.name: f.number for f in shape.fields} == {f.name: f.number for f in SHAPE.fields}
    assert shape.fields_by_name["ids"].is_packed and not shape.fields_by_name["points"].is_packed
    assert [f.name for f in shape.oneofs_by_name["form"].fields] == ["circle", "label"]
    point = classes["Point"].DESCRIPTOR
    assert point.fields_by_name["y"].type == descriptor.FieldDescriptor.TYPE_FLOAT
    msg = classes["Shape"](colour=COLOUR.number("GREEN"), label="a")
    msg.circle.x = 1.0  # the oneof: setting one member clears the other
    assert msg.WhichOneof("form") == "circle" and msg.label == ""


def test_womd_classes_carry_the_public_full_names() -> None:
    assert womd_messages.Track.DESCRIPTOR.full_name == "waymo.open_dataset.Track"
    assert womd_messages.Track.ObjectType.Value("TYPE_CYCLIST") == 3
    assert womd_messages.RoadLine.RoadLineType.Value("TYPE_PASSING_DOUBLE_YELLOW") == 8
    boundary = womd_messages.BoundarySegment.DESCRIPTOR.fields_by_name["boundary_type"]
    assert boundary.enum_type.full_name == "waymo.open_dataset.RoadLine.RoadLineType"
    lane = womd_messages.LaneCenter.DESCRIPTOR
    assert lane.fields_by_name["exit_lanes"].is_packed and not lane.fields_by_name["left_neighbors"].is_packed
    feature = womd_messages.MapFeature.DESCRIPTOR
    assert len(feature.oneofs_by_name["feature_data"].fields) == 7
    assert file_descriptor("x.proto", "waymo.open_dataset", (SCENARIO,)).syntax == "proto2"


def test_schema_errors_name_the_message_or_field() -> None:
    untyped = MessageSchema("Bad", (Field(1, "kind", "enum"),))
    with pytest.raises(ValueError, match=r"Bad\.kind"):
        file_descriptor("bad.proto", "test.pkg", (untyped,))
    other_point = MessageSchema("Point", (Field(1, "x", "float"),))
    clash = MessageSchema(
        "Pair", (Field(1, "a", "message", message=POINT), Field(2, "b", "message", message=other_point))
    )
    with pytest.raises(ValueError, match="Point"):
        file_descriptor("clash.proto", "test.pkg", (clash,))
    with pytest.raises(ValueError, match="packed"):
        Field(1, "name", "string", repeated=True, packed=True)
    with pytest.raises(ValueError, match="not a Colour value"):
        COLOUR.number("BLUE")


def test_fixed_width_records_equal_the_runtime_serialization() -> None:
    classes = message_classes("test/shape.proto", "test.pkg", (SHAPE,))
    rng = np.random.default_rng(0)
    values = np.column_stack([rng.normal(size=5) * 1e3, rng.normal(size=5), [1, 0, 1, 1, 0]])
    records = fixed_width_records(field_named(SHAPE, "points"), ("x", "y", "ok"), values)
    expected = classes["Shape"](points=[classes["Point"](x=x, y=y, ok=bool(ok)) for x, y, ok in values])
    assert records.tobytes() == expected.SerializeToString()  # field 20: a two-byte tag
    assert records.shape == (5, records.shape[1]) and records.dtype == np.uint8


def test_object_state_records_equal_the_runtime_serialization() -> None:
    rng = np.random.default_rng(1)
    values = np.column_stack([rng.normal(size=(4, len(STATE_COLUMNS))) * 50.0, np.ones(4)])
    records = fixed_width_records(field_named(TRACK, "states"), (*STATE_COLUMNS, "valid"), values)
    states = [womd_messages.ObjectState(**dict(zip(STATE_COLUMNS, row[:-1].tolist())), valid=True) for row in values]
    assert records.tobytes() == womd_messages.Track(states=states).SerializeToString()
    invalid = fixed_width_records(field_named(TRACK, "states"), ("valid",), np.zeros((1, 1)))
    assert invalid.tobytes() == womd_messages.Track(states=[womd_messages.ObjectState(valid=False)]).SerializeToString()


def test_fixed_width_records_reject_other_fields() -> None:
    with pytest.raises(ValueError, match="repeated message"):
        fixed_width_records(field_named(SHAPE, "colour"), ("x",), np.zeros((1, 1)))
    with pytest.raises(ValueError, match=r"Track\.id: not a singular fixed-width field \(int32\)"):
        fixed_width_records(field_named(SCENARIO, "tracks"), ("id",), np.zeros((1, 1)))
    with pytest.raises(ValueError, match=r"'states': values must be \[N, 2\]"):
        fixed_width_records(field_named(TRACK, "states"), ("valid", "center_x"), np.zeros((2, 1)))
    with pytest.raises(KeyError, match="ObjectState has no field 'speed'"):
        fixed_width_records(field_named(TRACK, "states"), ("speed",), np.zeros((2, 1)))
