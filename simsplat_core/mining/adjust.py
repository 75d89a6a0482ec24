"""The next attempt's program: a judge's parameter changes, or a default change by failure class, applied to an
executed :class:`~simsplat_core.editing.commands.EditProgram` (pydantic ``model_copy``; the program is a value).

    adjusted = adjust_program(program, kinds, judgement.suggestions, {"collision"}, alternative_asset=pick)
    adjusted.program, adjusted.changes          # None: nothing applies (the loop moves on)

Each :class:`~simsplat_core.mining.vlm_protocol.ParameterChange` is applied to every command it fits (the first
suggestion of each parameter only), its ``value`` read for a number and a direction:

* ``speed`` -- ``"7.5 m/s"`` (``km/h``, ``mph``) sets that speed; ``"slower"`` / ``"faster"`` scale the asked
  speed by :data:`SLOWER` / :data:`FASTER` (a ``delta`` speed moves by :data:`SPEED_STEP_KMH`); commands that move
  an agent only (``edit_kinds.moves``);
* ``start_time`` -- ``"2 s later"`` adds to ``behaviour.delay_s`` (later than the attempt just judged, so repeated
  suggestions keep moving the start), ``"1 s earlier"`` takes from the delay (or the start time), a bare ``"3 s"``
  sets ``start_time_s``; moving agents only;
* ``offset`` -- ``"5 m further"`` / ``"away"`` / ``"another spot"`` move the placement that much further from its
  anchor (``distance_m``; from the editor's default distance when none was asked, ``editing.placement.resolve`` and
  ``editing.ops.DEFAULT_AHEAD_M``; an ``absolute`` position along its bearing), ``"closer"`` nearer (not
  within :data:`MIN_LANE_GAP_M` along a lane, :data:`MIN_SIDE_GAP_M` beside the anchor); ``"... lane centre"``
  shrinks a ``behaviour.lateral_offset_m`` towards 0; commands with a placement (an insert always has one);
* ``anchor`` -- a placement relative to an object is made relative to the ego (the anchor dropped);
* ``asset`` -- the inserted or swapped-in asset is pinned (``AssetSpec.asset_id``) to ``alternative_asset(spec)``:
  the loop gives the bank's best match that was not used yet (``AssetBank.retrieve(..., exclude=...)``; the editor's
  ``apply_edit`` takes no excluded assets, so the choice is made here and pinned);
* ``other`` -- not applied.

Default changes when no suggestion changes anything (:data:`DEFAULT_ORDER`): a ``collision`` starts the moving
agents :data:`DEFAULT_DELAY_S` later, or puts a standing insert :data:`DEFAULT_OFFSET_M` further away; ``offroad``
drops the anchor, or centres the lateral offset; ``not_visible`` brings the insert :data:`DEFAULT_OFFSET_M` closer;
``infeasible_placement`` (a refused placement) tries :data:`DEFAULT_OFFSET_M` further. Everything is a pure function
of its inputs (no clock, no random numbers).
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass

from simsplat_core.editing.commands import (
    SPEED_UNITS,
    AssetSpec,
    Behaviour,
    EditCommand,
    EditProgram,
    Placement,
    SpeedSpec,
    TargetRef,
)
from simsplat_core.editing.ops import DEFAULT_AHEAD_M
from simsplat_core.editing.placement.resolve import LANE_AHEAD_M, LONG_GAP_M, SIDE_GAP_M
from simsplat_core.mining.edit_kinds import moves
from simsplat_core.mining.vlm_protocol import ParameterChange
from simsplat_core.scenario.vocabulary import PEDESTRIAN

logger = logging.getLogger(__name__)

#: Speed factors of a "slower" / "faster" suggestion without a number, and the step of a ``delta`` speed (km/h).
SLOWER, FASTER = 0.7, 1.3
SPEED_STEP_KMH = 5.0
#: Seconds added by a "later" suggestion without a number, and by the default change of a collision.
LATER_S = 2.0
DEFAULT_DELAY_S = 1.5
#: Metres moved by an offset suggestion without a number, and by the default changes.
OFFSET_STEP_M = 5.0
DEFAULT_OFFSET_M = 5.0
#: A placement is brought no closer than this to its anchor: along a lane / area, and beside it (m).
MIN_LANE_GAP_M = 8.0
MIN_SIDE_GAP_M = 0.5
#: Failure classes with a default change, in the order they are tried.
DEFAULT_ORDER: tuple[str, ...] = ("collision", "offroad", "not_visible", "infeasible_placement")
#: Limits of the command schema.
_MAX_DELAY_S, _MAX_DISTANCE_M, _MAX_LATERAL_M, _MAX_FACTOR = 60.0, 300.0, 10.0, 10.0
_BESIDE = frozenset({"left_of", "right_of", "next_to", "in_front_of", "behind"})
_NUMBER = re.compile(r"(\d+(?:\.\d+)?)")
_SPEED = re.compile(r"(\d+(?:\.\d+)?)\s*(m/s|km/h|kph|mph)")

#: ``alternative_asset(spec)``: an asset id to pin instead of ``spec``'s choice (``None``: no other fits).
AlternativeAsset = Callable[[AssetSpec], str | None]


@dataclass(frozen=True)
class Adjustment:
    """The next attempt's program and what changed, one line per change (``"command 1: delay 0 -> 2 s"``)."""

    program: EditProgram
    changes: tuple[str, ...]

    def describe(self) -> str:
        return "; ".join(self.changes)


def _amount(value: str, default: float) -> float:
    found = _NUMBER.search(value)
    return float(found[1]) if found else default


def _has(value: str, *words: str) -> bool:
    return any(w in value for w in words)


def _behaviour(command: EditCommand) -> Behaviour:
    return command.behaviour or Behaviour()


def _with_behaviour(command: EditCommand, **update: object) -> EditCommand:
    return command.model_copy(update={"behaviour": _behaviour(command).model_copy(update=update)})


# ---------------------------------------------------------------------------------------------- per parameter
def change_speed(command: EditCommand, value: str) -> EditCommand | None:
    """``command`` with the speed ``value`` asks for (module docstring), ``None`` when it asks nothing readable."""
    text = value.lower()
    asked = _SPEED.search(text)
    if asked:
        unit = "km/h" if asked[2] == "kph" else asked[2]
        mps = min(float(asked[1]) * SPEED_UNITS[unit], 70.0)
        speed = SpeedSpec.model_validate({"mode": "absolute", "value": round(mps / SPEED_UNITS[unit], 2), "unit": unit})
        return _with_behaviour(command, speed=speed)
    slower, faster = _has(text, "slower", "lower", "less", "reduce"), _has(text, "faster", "higher", "more", "raise")
    if slower == faster:
        return None
    factor = SLOWER if slower else FASTER
    now = _behaviour(command).speed
    if now is None:
        speed = SpeedSpec(mode="factor", value=factor)
    elif now.mode == "delta":
        step = SPEED_STEP_KMH / 3.6 / SPEED_UNITS[now.unit]
        speed = now.model_copy(update={"value": now.value + (step if faster else -step)})
    elif now.mode == "factor":
        speed = now.model_copy(update={"value": min(now.value * factor, _MAX_FACTOR)})
    else:
        speed = now.model_copy(update={"value": min(now.value * factor, 70.0 / SPEED_UNITS[now.unit])})
    return _with_behaviour(command, speed=speed)


def change_start(command: EditCommand, value: str) -> EditCommand | None:
    """``command`` starting when ``value`` says (module docstring), ``None`` when that changes nothing."""
    text = value.lower()
    behaviour = _behaviour(command)
    if _has(text, "earlier", "sooner"):
        step = _amount(text, 1.0)
        if behaviour.start_time_s is not None and behaviour.start_time_s > 0:
            return _with_behaviour(command, start_time_s=max(0.0, behaviour.start_time_s - step))
        if behaviour.delay_s:
            delay = max(0.0, behaviour.delay_s - step)
            return _with_behaviour(command, delay_s=delay or None)
        return None
    if _has(text, "later", "delay", "wait", "after") or not _NUMBER.search(text):
        delay = min((behaviour.delay_s or 0.0) + _amount(text, LATER_S), _MAX_DELAY_S)
        return None if delay == behaviour.delay_s else _with_behaviour(command, delay_s=delay)
    start = _amount(text, 0.0)
    return None if start == behaviour.start_time_s else _with_behaviour(command, start_time_s=start)


def asked_placement(command: EditCommand, kind: str | None) -> Placement | None:
    """The placement ``command`` was executed with: its own, or for an insert the editor's default (pedestrians on
    the sidewalk, everything else in the ego lane, ``DEFAULT_AHEAD_M`` ahead)."""
    if command.placement is not None or command.op != "insert":
        return command.placement
    if kind == PEDESTRIAN:
        return Placement(relation="on_sidewalk", distance_m=DEFAULT_AHEAD_M)
    return Placement(relation="in_lane", lane="same", distance_m=DEFAULT_AHEAD_M)


def _default_distance(placement: Placement) -> float:
    """The distance the editor uses when a placement asks none (``editing.placement.resolve``)."""
    if placement.relation == "in_lane":
        return LANE_AHEAD_M
    if placement.relation in ("in_front_of", "behind"):
        return LONG_GAP_M
    if placement.relation in _BESIDE:
        return SIDE_GAP_M
    return 0.0  # an area's nearest spot


def moved_placement(placement: Placement, metres: float) -> Placement | None:
    """``placement`` ``metres`` further from its anchor (negative: closer; module docstring), ``None`` when it
    cannot move."""
    if placement.relation == "absolute":
        assert placement.position is not None
        x, y, z = placement.position
        reach = math.hypot(x, y)
        if reach < 1e-6:
            return None
        new = max(reach + metres, MIN_SIDE_GAP_M)
        return placement.model_copy(update={"position": (x * new / reach, y * new / reach, z)})
    least = MIN_SIDE_GAP_M if placement.relation in _BESIDE else MIN_LANE_GAP_M
    now = placement.distance_m if placement.distance_m is not None else _default_distance(placement)
    new = round(min(max(now + metres, least if metres < 0 else 0.0), _MAX_DISTANCE_M), 2)
    return None if math.isclose(new, now) or (metres < 0 and new >= now) else placement.model_copy(
        update={"distance_m": new})


def change_offset(command: EditCommand, kind: str | None, value: str) -> EditCommand | None:
    """``command`` with the placement ``value`` asks for (module docstring), ``None`` when it does not apply."""
    text = value.lower()
    if _has(text, "centre", "center", "lateral", "sideways", "towards the lane"):
        lateral = _behaviour(command).lateral_offset_m
        if not lateral:
            return None
        step = _amount(text, 1.0)
        shrunk = math.copysign(max(abs(lateral) - step, 0.0), lateral)
        return _with_behaviour(command, lateral_offset_m=max(-_MAX_LATERAL_M, min(_MAX_LATERAL_M, shrunk)) or None)
    placement = asked_placement(command, kind)
    if placement is None:
        return None
    closer = _has(text, "closer", "nearer")
    metres = _amount(text, OFFSET_STEP_M)
    moved = moved_placement(placement, -metres if closer else metres)
    return None if moved is None else command.model_copy(update={"placement": moved})


def change_anchor(command: EditCommand) -> EditCommand | None:
    """``command`` placed relative to the ego instead of an object, ``None`` when it already is."""
    placement = command.placement
    if placement is None or placement.anchor is None or placement.anchor.is_ego:
        return None
    return command.model_copy(update={"placement": placement.model_copy(update={"anchor": None})})


def change_asset(command: EditCommand, kind: str | None, alternative: AlternativeAsset | None) -> EditCommand | None:
    """``command`` with its asset pinned to ``alternative(spec)`` (``None``: no other asset fits); the spec asked
    of ``alternative`` names the category ``kind`` when it names none, so a swap keeps the kind of agent."""
    spec = command.asset
    if spec is None or alternative is None or command.op not in ("insert", "replace"):
        return None
    asked = spec if spec.category is not None or kind is None else spec.model_copy(update={"category": kind})
    other = alternative(asked)
    if other is None or other == spec.asset_id:
        return None
    return command.model_copy(update={"asset": spec.model_copy(update={"asset_id": other})})


def apply_change(command: EditCommand, kind: str | None, change: ParameterChange,
                 alternative_asset: AlternativeAsset | None = None) -> EditCommand | None:
    """``command`` after ``change`` (module docstring), ``None`` when the change does not apply to it."""
    if change.parameter in ("speed", "start_time"):
        if not moves(command, kind):
            return None
        return (change_speed if change.parameter == "speed" else change_start)(command, change.value)
    if change.parameter == "offset":
        return change_offset(command, kind, change.value)
    if change.parameter == "anchor":
        return change_anchor(command)
    if change.parameter == "asset":
        return change_asset(command, kind, alternative_asset)
    return None


# ---------------------------------------------------------------------------------------------- programs
def _describe(index: int, change: ParameterChange) -> str:
    return f"command {index + 1}: {change.parameter} {change.value}".rstrip()


def _applied(program: EditProgram, kinds: Sequence[str | None], changes: Sequence[ParameterChange],
             alternative_asset: AlternativeAsset | None) -> Adjustment | None:
    """``changes`` applied to every command they fit; ``None`` when nothing changed."""
    commands = list(program.commands)
    lines = []
    for change in changes:
        for i, command in enumerate(commands):
            kind = kinds[i] if i < len(kinds) else None
            new = apply_change(command, kind, change, alternative_asset)
            if new is not None and new != command:
                commands[i] = new
                lines.append(_describe(i, change))
    if not lines:
        return None
    return Adjustment(program.model_copy(update={"commands": commands}), tuple(lines))


def default_changes(failure: str, program: EditProgram, kinds: Sequence[str | None]) -> list[ParameterChange]:
    """The default changes of one failure class (module docstring)."""
    moving = any(moves(c, kinds[i] if i < len(kinds) else None) for i, c in enumerate(program.commands))
    if failure == "collision":
        if moving:
            return [ParameterChange("start_time", f"{DEFAULT_DELAY_S:g} s later", "default for a collision")]
        return [ParameterChange("offset", f"{DEFAULT_OFFSET_M:g} m further", "default for a collision")]
    if failure == "offroad":
        return [ParameterChange("anchor", "the ego", "default for off-road"),
                ParameterChange("offset", "1 m towards the lane centre", "default for off-road")]
    if failure == "not_visible":
        return [ParameterChange("offset", f"{DEFAULT_OFFSET_M:g} m closer", "default when the target is not seen")]
    if failure == "infeasible_placement":
        return [ParameterChange("offset", f"{DEFAULT_OFFSET_M:g} m further", "default for a refused placement")]
    return []


def adjust_program(program: EditProgram, kinds: Sequence[str | None], suggestions: Sequence[ParameterChange] = (),
                   failures: Collection[str] = (), *, alternative_asset: AlternativeAsset | None = None
                   ) -> Adjustment | None:
    """The next attempt's program (module docstring): the first suggestion of each parameter, else the default
    changes of the first class in ``failures`` (:data:`DEFAULT_ORDER`) that changes something; ``None`` when
    nothing does. ``kinds``: per command, the kind of agent it acts on (``edit_kinds.command_kinds``)."""
    firsts: list[ParameterChange] = []
    for s in suggestions:
        if all(f.parameter != s.parameter for f in firsts):
            firsts.append(s)
    adjusted = _applied(program, kinds, firsts, alternative_asset)
    if adjusted is not None:
        return adjusted
    for failure in DEFAULT_ORDER:
        if failure in failures:
            adjusted = _applied(program, kinds, default_changes(failure, program, kinds), alternative_asset)
            if adjusted is not None:
                return adjusted
    return None



def retarget(program: EditProgram, command_index: int | None, object_id: str) -> Adjustment | None:
    """The next attempt after the words of a command's object did not ground (a ``not_found`` refusal): that
    command (``None``: the first) acts on -- or, for an insert, is placed by -- ``object_id``, the object the
    proposer meant (``Pending.target_id``), by id. ``None`` when the command names no object by description (a
    group, an id, the ego) or already names ``object_id``."""
    index = command_index or 0
    if not 0 <= index < len(program.commands):
        return None
    command = program.commands[index]
    by_id = TargetRef(object_id=object_id)
    if command.op == "insert":
        anchor = command.placement.anchor if command.placement is not None else None
        if anchor is None or anchor.description is None or anchor.is_ego or anchor.group:
            return None
        assert command.placement is not None
        changed = command.model_copy(update={"placement": command.placement.model_copy(update={"anchor": by_id})})
        what = f"anchor {anchor.description!r}"
    else:
        target = command.target
        if target is None or target.description is None or target.group:
            return None
        changed = command.model_copy(update={"target": by_id})
        what = f"target {target.description!r}"
    commands = [*program.commands[:index], changed, *program.commands[index + 1:]]
    return Adjustment(program.model_copy(update={"commands": commands}),
                      (f"command {index + 1}: {what} -> object {object_id} (the proposer's referent; the words did "
                       "not ground)",))


__all__ = ["DEFAULT_DELAY_S", "DEFAULT_OFFSET_M", "DEFAULT_ORDER", "Adjustment", "AlternativeAsset", "adjust_program",
           "apply_change", "asked_placement", "change_anchor", "change_asset", "change_offset", "change_speed",
           "change_start", "default_changes", "moved_placement", "retarget"]
