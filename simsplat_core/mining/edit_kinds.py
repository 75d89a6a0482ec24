"""What kind of agent each command of an edit program acts on, and the program's edit category (the ``editing``
table's six: ``rule_proposals.EDIT_CATEGORIES``).

    kinds = command_kinds(program, ctx.states, edited)     # ["vehicle"], ["static"], [None] ...
    edit_category(program, kinds)                           # "add_vehicle", "modify_pedestrian", "remove" ...

A command's kind (``"vehicle"``, ``"pedestrian"`` or ``"static"``: ``scenario.metrics.kind_of``) comes from, in
order: the agents the executed edit added or changed (``edited``), the target's log category (``target.object_id``),
the asked asset category, and for a modify the behaviour (crossing, jaywalking or a gait are pedestrian-only);
``None`` when nothing tells. The category is the first command's: ``insert`` -> ``add_<kind>``, ``remove`` ->
``remove``, ``modify`` / ``replace`` -> ``modify_<kind>`` (a static target counts as a vehicle there: the table has no
``modify_static``); an unknown kind counts as a vehicle.
"""

from __future__ import annotations

from simsplat_core.editing.commands import EditCommand, EditProgram
from simsplat_core.editing.result import EditedScene
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.metrics import STATIC, kind_of
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE


def _kind_in(states: AgentStates, object_ids: tuple[str, ...]) -> str | None:
    found = [o for o in object_ids if o in states.object_ids]
    return kind_of(states.categories[states.index(found[0])]) if found else None


def command_kind(command: EditCommand, states: AgentStates, edited_ids: tuple[str, ...] = (),
                 edited_states: AgentStates | None = None) -> str | None:
    """The kind of agent ``command`` acts on (module docstring): ``edited_ids`` are the agents the executed command
    added or changed (in ``edited_states``, else in ``states``), ``states`` the log's agents."""
    if edited_ids:
        kind = _kind_in(edited_states, edited_ids) if edited_states is not None else None
        kind = kind or _kind_in(states, edited_ids)
        if kind is not None:
            return kind
    if command.target is not None and command.target.object_id is not None:
        kind = _kind_in(states, (command.target.object_id,))
        if kind is not None:
            return kind
    if command.asset is not None and command.asset.category is not None:
        return command.asset.category
    behaviour = command.behaviour
    if command.op == "modify" and behaviour is not None and (behaviour.cross_street or behaviour.gait is not None):
        return PEDESTRIAN
    return None


def command_kinds(program: EditProgram, states: AgentStates, edited: EditedScene | None = None) -> list[str | None]:
    """Per command of ``program``, :func:`command_kind` (with the outcomes of ``edited``, its execution)."""
    if edited is None or len(edited.outcomes) != len(program.commands):
        return [command_kind(c, states) for c in program.commands]
    return [command_kind(c, states, tuple(dict.fromkeys((*o.new_object_ids, *o.changed_object_ids))),
                         edited.original_states if c.op == "remove" else edited.states)
            for c, o in zip(program.commands, edited.outcomes)]


def edit_category(program: EditProgram, kinds: list[str | None]) -> str:
    """The program's edit category from its first command and that command's kind (module docstring)."""
    command, kind = program.commands[0], kinds[0] if kinds else None
    if command.op == "remove":
        return "remove"
    if command.op == "insert":
        return f"add_{kind or VEHICLE}"
    return f"modify_{PEDESTRIAN if kind == PEDESTRIAN else VEHICLE}"


def moves(command: EditCommand, kind: str | None) -> bool:
    """``command`` makes an agent move, so its speed and start time can change: a modify, or an insert of a
    vehicle or a pedestrian (static objects stand; a replace keeps the trajectory; a remove has none)."""
    return command.op == "modify" or (command.op == "insert" and kind is not None and kind != STATIC)


__all__ = ["command_kind", "command_kinds", "edit_category", "moves"]
