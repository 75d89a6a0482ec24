"""The edit command language: one validated pydantic schema for every edit, whoever writes it.

The offline parser (``editing.parse.prompt``), a VLM's function calling (``mining.openai_vlm``) and hand-written
JSON all produce :class:`EditCommand` s; nothing runs before a command validates (ChatSim ``eval()``-s model text:
here a malformed command is a :class:`pydantic.ValidationError` that names the field). The JSON Schema
(:func:`edit_program_json_schema`) is what a function-calling model is given.

Ops:

* ``insert`` -- add ``asset`` at ``placement`` (optionally with a ``behaviour``); ``asset.count > 1`` places a row.
* ``remove`` -- drop ``target`` (a group target drops every match).
* ``replace`` -- swap ``target``'s appearance for ``asset``, keep its trajectory (the box is refitted).
* ``modify`` -- change ``target``'s trajectory by ``behaviour`` (and/or move it to ``placement``).

Frames: ``Placement.position`` is in the ego frame (x forward, y left, z up, metres) at ``Placement.frame``;
headings are degrees counter-clockwise from the ego's x axis. Times are seconds from the log's first frame.
"""

from __future__ import annotations

import json
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

#: Schema identifier written beside persisted commands (``command.json``).
COMMAND_SCHEMA_VERSION = "simsplat-edit-command/1"
#: ``TargetRef.description`` that names the ego vehicle (an anchor only: the ego is never edited).
EGO = "ego"
#: Speed units understood by :class:`SpeedSpec` and their factor to m/s.
SPEED_UNITS: dict[str, float] = {"m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704}

Op = Literal["insert", "remove", "replace", "modify"]
AssetCategory = Literal["vehicle", "pedestrian", "static"]
#: Where a placement is, relative to its anchor (the ego when ``anchor`` is ``None``):
#: ``left_of`` / ``right_of`` / ``in_front_of`` / ``behind`` / ``next_to`` -- beside the anchor in its own frame;
#: ``in_lane`` -- in a lane (``lane``) ``distance_m`` ahead of the anchor along the lane graph;
#: ``on_crosswalk`` / ``on_sidewalk`` / ``on_road`` -- on that kind of map area nearest the anchor (``distance_m``
#: ahead of it when given); ``absolute`` -- at ``position`` (ego frame at ``frame``).
Relation = Literal["left_of", "right_of", "in_front_of", "behind", "next_to", "in_lane", "on_crosswalk",
                   "on_sidewalk", "on_road", "absolute"]
#: Lane of an ``in_lane`` placement, relative to the anchor's lane.
LaneChoice = Literal["same", "left", "right", "opposite"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class TargetRef(_Strict):
    """An object (or group) an edit acts on or is placed relative to: exactly one of ``description``,
    ``node_id`` or ``object_id``. ``group=True`` means every object the description matches ("all crossing
    pedestrians", "every parked car"); ``description="ego"`` names the ego (anchors only)."""

    description: str | None = Field(default=None, min_length=1, max_length=300,
                                    description="Free-form description, e.g. 'the white van on the left', or 'ego'.")
    node_id: int | None = Field(default=None, ge=1, description="Scene-graph node id (as printed by `simsplat query`).")
    object_id: str | None = Field(default=None, min_length=1, description="The log's object id.")
    group: bool = Field(default=False, description="Act on every object the description matches.")

    @model_validator(mode="after")
    def _one_reference(self) -> TargetRef:
        given = [name for name in ("description", "node_id", "object_id") if getattr(self, name) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of description, node_id, object_id (got {given or 'none'})")
        if self.group and self.description is None:
            raise ValueError("group=True needs a description (ids name one object)")
        return self

    @property
    def is_ego(self) -> bool:
        return self.description is not None and self.description.strip().lower() in (EGO, "the ego", "ego vehicle")


class AssetSpec(_Strict):
    """What to insert (or to replace with): a description matched against the asset bank, narrowed by
    ``category`` / ``color`` / ``subtype`` / ``size_m`` when given; ``asset_id`` picks one asset exactly."""

    description: str = Field(min_length=1, max_length=300, description="e.g. 'a yellow taxi', 'a row of orange cones'.")
    category: AssetCategory | None = None
    subtype: str | None = Field(default=None, description="e.g. 'taxi', 'bus', 'traffic cone', 'barrier'.")
    color: str | None = Field(default=None, description="A colour name, e.g. 'yellow'.")
    size_m: tuple[float, float, float] | None = Field(default=None, description="Wanted box (length, width, height).")
    count: int = Field(default=1, ge=1, le=20, description="How many (a row of cones: several, spaced along the lane).")
    spacing_m: float | None = Field(default=None, gt=0, le=50, description="Gap between the objects of a row.")
    asset_id: str | None = None


class Placement(_Strict):
    """Where an inserted (or moved) object goes; see :data:`Relation`."""

    relation: Relation
    anchor: TargetRef | None = Field(default=None, description="Reference object; None = the ego.")
    distance_m: float | None = Field(default=None, ge=0, le=300, description="Gap from the anchor (relation-specific).")
    lane: LaneChoice | None = Field(default=None, description="For in_lane: which lane relative to the anchor's.")
    position: tuple[float, float, float] | None = Field(default=None, description="For absolute: ego x, y, z (m).")
    heading_deg: float | None = Field(default=None, ge=-360, le=360, description="Heading in the ego frame (deg, CCW).")
    frame: int | None = Field(default=None, ge=0, description="Frame the placement refers to (default: the first).")

    @model_validator(mode="after")
    def _position_for_absolute(self) -> Placement:
        if (self.relation == "absolute") != (self.position is not None):
            raise ValueError("relation 'absolute' needs position, and position is only for 'absolute'")
        if self.lane is not None and self.relation != "in_lane":
            raise ValueError("lane is only for relation 'in_lane'")
        return self


class SpeedSpec(_Strict):
    """A target speed: ``absolute`` (``value`` in ``unit``), ``factor`` ("twice as fast": 2.0) or ``delta``
    ("10 km/h slower": -10, ``unit='km/h'``)."""

    mode: Literal["absolute", "factor", "delta"] = "absolute"
    value: float
    unit: Literal["m/s", "km/h", "mph"] = "m/s"

    @model_validator(mode="after")
    def _sane(self) -> SpeedSpec:
        if self.mode == "absolute" and not 0 <= self.value * SPEED_UNITS[self.unit] <= 70:
            raise ValueError(f"absolute speed must be within 0..70 m/s, got {self.value} {self.unit}")
        if self.mode == "factor" and not 0 <= self.value <= 10:
            raise ValueError(f"speed factor must be within 0..10, got {self.value}")
        return self

    def target_mps(self, current_mps: float) -> float:
        """The requested speed in m/s given the agent's current speed (never negative)."""
        if self.mode == "factor":
            return max(0.0, current_mps * self.value)
        if self.mode == "delta":
            return max(0.0, current_mps + self.value * SPEED_UNITS[self.unit])
        return self.value * SPEED_UNITS[self.unit]


class StopSpec(_Strict):
    """Where / when to stop: at a time, before the next crosswalk / intersection, or behind an object (all
    ``None``: stop as soon as comfortably possible)."""

    at_time_s: float | None = Field(default=None, ge=0)
    before: Literal["crosswalk", "intersection", "stop_line"] | None = None
    behind: TargetRef | None = None
    gap_m: float | None = Field(default=None, ge=0, le=50, description="Distance kept to what it stops before/behind.")


class Behaviour(_Strict):
    """How an agent moves; unset fields keep the log's behaviour. Vehicle-only: ``lane_change``, ``turn``,
    ``reverse``, ``follow``; pedestrian-only: ``cross_street``, ``jaywalk``, ``gait``."""

    speed: SpeedSpec | None = None
    longitudinal: Literal["accelerate", "decelerate", "brake_hard"] | None = None
    stop: StopSpec | None = None
    reverse: bool = False
    lane_change: Literal["left", "right"] | None = None
    turn: Literal["left", "right", "straight"] | None = Field(default=None, description="At the next intersection.")
    start_time_s: float | None = Field(default=None, ge=0, description="Stands still until this time.")
    delay_s: float | None = Field(default=None, ge=0, le=60, description="Starts this much later than in the log.")
    follow: TargetRef | None = None
    cross_street: bool = False
    jaywalk: bool = Field(default=False, description="Cross away from any crosswalk.")
    gait: Literal["walk", "run"] | None = None
    lateral_offset_m: float | None = Field(default=None, ge=-10, le=10, description="Shift sideways (+ = left).")

    @model_validator(mode="after")
    def _consistent(self) -> Behaviour:
        if self.reverse and (self.turn is not None or self.lane_change is not None):
            raise ValueError("reverse cannot be combined with turn or lane_change")
        if self.turn is not None and self.lane_change is not None:
            raise ValueError("give turn or lane_change, not both")
        if self.jaywalk and not self.cross_street:
            object.__setattr__(self, "cross_street", True)
        return self

    @property
    def is_empty(self) -> bool:
        return self == Behaviour()


class EditCommand(_Strict):
    """One edit. Required per op: insert -> asset (+ placement, default: in the ego lane ahead); remove ->
    target; replace -> target + asset; modify -> target + behaviour and/or placement."""

    op: Op
    target: TargetRef | None = None
    asset: AssetSpec | None = None
    placement: Placement | None = None
    behaviour: Behaviour | None = None
    note: str = Field(default="", max_length=500, description="The words this command came from (for messages).")

    @model_validator(mode="after")
    def _fields_for_op(self) -> EditCommand:
        need = {"insert": ("asset",), "remove": ("target",), "replace": ("target", "asset"), "modify": ("target",)}
        missing = [name for name in need[self.op] if getattr(self, name) is None]
        if missing:
            raise ValueError(f"op '{self.op}' needs {', '.join(missing)}")
        if self.op == "modify" and self.behaviour is None and self.placement is None:
            raise ValueError("op 'modify' needs behaviour or placement")
        if self.op == "insert" and self.target is not None:
            raise ValueError("op 'insert' takes no target (place it with placement.anchor)")
        if self.op == "remove" and (self.asset is not None or self.behaviour is not None):
            raise ValueError("op 'remove' takes only a target")
        if self.target is not None and self.target.is_ego:
            raise ValueError("the ego vehicle cannot be edited")
        return self


class EditProgram(_Strict):
    """A prompt and the commands it means, applied in order."""

    prompt: str = ""
    commands: list[EditCommand] = Field(min_length=1)
    schema_version: str = COMMAND_SCHEMA_VERSION


def edit_program_json_schema() -> dict[str, Any]:
    """JSON Schema of :class:`EditProgram` (what a function-calling VLM is given)."""
    return EditProgram.model_json_schema()


def edit_command_json_schema() -> dict[str, Any]:
    """JSON Schema of one :class:`EditCommand`."""
    return EditCommand.model_json_schema()


def program_from_json(text: str | bytes, source: str = "command JSON") -> EditProgram:
    """Validate an :class:`EditProgram` (or a bare list of commands / one command) from JSON.

    Raises:
        pydantic.ValidationError: the message names ``source`` and each bad field's path.
    """
    data = json.loads(text)
    if isinstance(data, list):
        data = {"commands": data}
    elif isinstance(data, dict) and "op" in data:
        data = {"commands": [data]}
    return EditProgram.model_validate(data, context={"source": source})


def program_to_json(program: EditProgram) -> str:
    return program.model_dump_json(indent=2, exclude_defaults=False)
