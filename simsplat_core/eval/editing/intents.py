"""What an editing prompt asks for, in ground-truth terms, and its id-based command form.

An :class:`EditIntent` names objects by their ground-truth object ids (``"veh_03"``; ``"ego"`` for the
ego as an anchor) and quantities in SI units resolved against the ground truth ("twice as fast" for a
car doing 8 m/s is ``speed_mps = 16``). The success checks (``checks.py``) measure the edited scene
against it; :func:`intent_program` writes the same edit as an ``EditProgram`` that names objects by
scene-graph node id instead of words -- the input of the OmniRe-like baseline, which has no language
grounding.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from simsplat_core.editing.commands import Behaviour, EditCommand, EditProgram, TargetRef

#: The anchor name of the ego vehicle.
EGO = "ego"


@dataclass(frozen=True)
class AssetIntent:
    """The object to insert (or to replace with).

    Attributes:
        category: ``"vehicle"``, ``"pedestrian"`` or ``"static"``.
        subtype: catalogue name asked for (``"SUV"``, ``"traffic cone"``), ``None`` for a generic noun.
        color: vehicle / static colour asked for; upper / lower: clothing colours asked for.
        count: how many (a row of cones).
        description: the words (what an ``AssetSpec.description`` holds).
    """

    category: str
    subtype: str | None = None
    color: str | None = None
    upper: str | None = None
    lower: str | None = None
    count: int = 1
    description: str = ""


@dataclass(frozen=True)
class PlacementIntent:
    """Where an inserted object goes: ``relation`` (``commands.Relation``) to ``anchor`` (a ground-truth
    object id or :data:`EGO`), ``distance_m`` when said, ``lane`` for ``in_lane`` (``commands.LaneChoice``)."""

    relation: str
    anchor: str = EGO
    distance_m: float | None = None
    lane: str | None = None


@dataclass(frozen=True)
class SpeedWords:
    """A speed as worded: ``commands.SpeedSpec`` fields."""

    mode: str
    value: float
    unit: str


@dataclass(frozen=True)
class MotionIntent:
    """The behaviour asked for (unset fields: keep the log's behaviour).

    Attributes:
        speed_mps: the requested speed resolved against the ground truth (``speed`` as worded).
        longitudinal: ``"accelerate"`` / ``"decelerate"`` / ``"brake_hard"``.
        stop: come to a standstill; ``stop_before``: ``"crosswalk"``; ``stop_by_s``: standing by this time.
        reverse, lane_change (``"left"``/``"right"``), turn (``"left"``/``"right"``/``"straight"``),
        delay_s, cross_street, jaywalk, gait (``"walk"``/``"run"``): as in ``commands.Behaviour``.
    """

    speed_mps: float | None = None
    speed: SpeedWords | None = None
    longitudinal: str | None = None
    stop: bool = False
    stop_before: str | None = None
    stop_by_s: float | None = None
    reverse: bool = False
    lane_change: str | None = None
    turn: str | None = None
    delay_s: float | None = None
    cross_street: bool = False
    jaywalk: bool = False
    gait: str | None = None

    def behaviour(self) -> Behaviour:
        """The ``commands.Behaviour`` of this intent: its fields named as ``Behaviour``'s are taken as they are
        (:data:`_AS_IN_BEHAVIOUR`; a jaywalk is a crossing, ``Behaviour`` sets ``cross_street``), ``speed`` as
        worded and ``stop`` with where and by when."""
        fields: dict[str, object] = {name: getattr(self, name) for name in _AS_IN_BEHAVIOUR}
        if self.speed is not None:
            fields["speed"] = dataclasses.asdict(self.speed)
        if self.stop:
            fields["stop"] = {"before": self.stop_before, "at_time_s": self.stop_by_s}
        return Behaviour.model_validate(fields)


#: The ``MotionIntent`` fields that are ``Behaviour`` fields of the same name and meaning (not ``speed``, worded
#: differently, nor ``stop``, a flag here).
_AS_IN_BEHAVIOUR: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(MotionIntent)
                                          if f.name in Behaviour.model_fields and f.name not in ("speed", "stop"))


@dataclass(frozen=True)
class EditIntent:
    """One prompt's edit in ground-truth terms.

    Attributes:
        op: ``"insert"``, ``"remove"``, ``"modify"`` or ``"replace"``.
        targets: ground-truth object ids acted on (remove / modify / replace); every member of a group.
        group: the words name a group ("all parked cars").
        asset, placement, motion: what to insert, where, and how it (or the target) moves.
        expected_refusals: for infeasible prompts, the ``EditRefused.reason`` codes that name the problem
            (any refusal counts as refused; the reason is reported).
        structured: whether the edit has an id-based form (``False``: it names objects that do not exist, or
            is not an edit at all).
    """

    op: str
    targets: tuple[str, ...] = ()
    group: bool = False
    asset: AssetIntent | None = None
    placement: PlacementIntent | None = None
    motion: MotionIntent | None = None
    expected_refusals: tuple[str, ...] = ()
    structured: bool = True

    @property
    def infeasible(self) -> bool:
        return bool(self.expected_refusals)


def _ref(object_id: str, node_of_object: dict[str, int]) -> TargetRef:
    if object_id == EGO:
        return TargetRef(description=EGO)
    return TargetRef(node_id=node_of_object[object_id])


def intent_program(intent: EditIntent, node_of_object: dict[str, int], prompt: str = "") -> EditProgram | None:
    """The edit as commands naming objects by node id (``None`` when it has no id-based form).

    A group becomes one command per member; an ego anchor is ``Placement.anchor = None``.

    Raises:
        KeyError: a target or anchor has no node in ``node_of_object``.
    """
    if not intent.structured:
        return None
    command: dict[str, object] = {"op": intent.op}
    if intent.asset is not None:
        a = intent.asset
        command["asset"] = {"description": a.description or a.subtype or a.category, "category": a.category,
                            "subtype": a.subtype, "color": a.color if a.category != "pedestrian" else a.upper,
                            "count": a.count}
    if intent.placement is not None:
        p = intent.placement
        command["placement"] = {"relation": p.relation, "distance_m": p.distance_m, "lane": p.lane,
                                "anchor": None if p.anchor == EGO else _ref(p.anchor, node_of_object)}
    if intent.motion is not None and intent.op in ("insert", "modify"):
        behaviour = intent.motion.behaviour()
        if not behaviour.is_empty:
            command["behaviour"] = behaviour
    if intent.op == "insert":
        commands = [EditCommand.model_validate(command)]
    else:
        commands = [EditCommand.model_validate({**command, "target": _ref(t, node_of_object)}) for t in intent.targets]
    return EditProgram(prompt=prompt, commands=commands)


__all__ = ["EGO", "AssetIntent", "EditIntent", "MotionIntent", "PlacementIntent", "SpeedWords", "intent_program"]
