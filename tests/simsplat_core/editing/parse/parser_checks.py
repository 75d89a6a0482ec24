"""Field-by-field checks of parsed commands, shared by the parser's tests.

An expectation is a dict of dotted attribute paths of an ``EditCommand`` and the value expected there:

* ``"target.description~": "white van"`` -- the value contains the text (case-insensitive);
* ``"asset.count>": 1`` -- the value is greater;
* ``"behaviour.stop": "set"`` -- the value is not None;
* ``"behaviour.start_or_delay": 3.0`` -- ``start_time_s`` or ``delay_s`` equals the value;
* ``"placement": None`` -- the value is None; anything else -- equality (floats to 1e-6).
"""

from __future__ import annotations

from typing import Any

from simsplat_core.editing.commands import EditCommand


def _get(command: EditCommand, path: str) -> Any:
    value: Any = command
    for name in path.split("."):
        if value is None:
            return None
        if name == "start_or_delay":
            return value.start_time_s if value.start_time_s is not None else value.delay_s
        value = getattr(value, name)
    return value


def mismatches(command: EditCommand, expected: dict[str, Any]) -> list[str]:
    """What of ``expected`` the command does not meet (empty: it meets all)."""
    wrong = []
    for key, want in expected.items():
        path = key.rstrip("~>")
        got = _get(command, path)
        if key.endswith("~"):
            ok = isinstance(got, str) and want.lower() in got.lower()
        elif key.endswith(">"):
            ok = got is not None and got > want
        elif want == "set":
            ok = got is not None
        elif isinstance(want, float) and isinstance(got, (int, float)):
            ok = abs(got - want) < 1e-6
        else:
            ok = got == want
        if not ok:
            wrong.append(f"{key}: expected {want!r}, got {got!r}")
    return wrong


def program_mismatches(commands: list[EditCommand], expected: list[dict[str, Any]]) -> list[str]:
    if len(commands) != len(expected):
        return [f"expected {len(expected)} command(s), got {len(commands)}: "
                f"{[c.model_dump(mode='json', exclude_defaults=True) for c in commands]}"]
    return [f"command {i}: {m}" for i, (c, e) in enumerate(zip(commands, expected)) for m in mismatches(c, e)]
