"""Rewrite imports and mentions of what the CLI split moved, in place: ``python moves_cli.py DIR...``.

Handles ``from X import a, b`` (one line or parenthesised: moved names go to a new ``from NEW import ...`` line
beside it), ``import X`` of a renamed module and dotted / path mentions in .py, .md and .toml files. Run
``ruff check --fix`` afterwards to sort the imports.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

#: Renamed modules.
MODULES = {"storage.png": "storage.pictures"}
#: Moved names: (old module, name) -> new module.
NAMES = {
    ("flows.cli", "default_real_logs"): "flows.cli.evaluate",
    ("flows.cli", "SHARED_REAL_LOGS"): "flows.cli.evaluate",
    ("flows.pipeline", "plan_alignment"): "tasks.stages",
    ("flows.pipeline", "AlignmentPlan"): "tasks.stages",
    ("tasks.edit", "LoadedEdit"): "tasks.stored_edits",
    ("tasks.edit", "load_edit_context"): "tasks.stored_edits",
    ("tasks.edit", "edit_key"): "tasks.stored_edits",
    ("tasks.edit", "write_edit"): "tasks.stored_edits",
    ("tasks.edit", "rebuild_edit"): "tasks.stored_edits",
    ("tasks.edit", "EDIT_VERSION"): "tasks.stored_edits",
    ("tasks.edit", "Progress"): "tasks.stored_edits",
    ("tasks.edit", "BEFORE_AFTER_FRAMES"): "simsplat_core.viz.edit_pictures",
    ("tasks.edit", "edit_as_dict"): "tasks.answers",
    ("tasks.query", "answer_as_dict"): "tasks.answers",
    ("tasks.search", "search_as_dict"): "tasks.answers",
    ("simsplat_core.viz.images", "encode_mp4"): "storage.pictures",
}
FROM = re.compile(r"^(?P<indent>[ \t]*)from (?P<mod>[\w.]+) import (?P<names>\([^)]*\)|[^\n]*)", re.M)


def _rewrite_from(match: re.Match[str]) -> str:
    indent, mod, raw = match["indent"], match["mod"], match["names"]
    mod = MODULES.get(mod, mod)
    comment = ""
    body = raw.strip()
    if not body.startswith("(") and "#" in body:
        body, comment = body.split("#", 1)
        comment = "  #" + comment
    names = [n.strip() for n in body.strip("()").replace("\n", " ").split(",") if n.strip()]
    stay, moved = [], {}
    for name in names:
        target = NAMES.get((mod, name.split(" as ")[0].strip()))
        (moved.setdefault(target, []) if target else stay).append(name)
    if not moved:
        return f"{indent}from {mod} import {raw}" if mod != match["mod"] else match.group(0)
    lines = [f"{indent}from {mod} import {', '.join(stay)}{comment}"] if stay else []
    lines += [f"{indent}from {target} import {', '.join(ns)}" for target, ns in moved.items()]
    return "\n".join(lines)


def rewrite(text: str) -> str:
    text = FROM.sub(_rewrite_from, text)
    for old, new in MODULES.items():
        text = re.sub(rf"(?<![\w.]){re.escape(old)}(?![\w])", new, text)
        text = text.replace(old.replace(".", "/") + ".py", new.replace(".", "/") + ".py")
    for (old, name), new in NAMES.items():
        text = re.sub(rf"(?<![\w.]){re.escape(old)}\.{name}(?!\w)", f"{new}.{name}", text)
    return text


def main(paths: list[str]) -> None:
    for root in paths:
        for path in Path(root).rglob("*"):
            if path.suffix not in (".py", ".md", ".toml") or ".venv" in path.parts or path.name == Path(__file__).name:
                continue
            text = path.read_text(encoding="utf-8")
            new = rewrite(text)
            if new != text:
                path.write_text(new, encoding="utf-8")
                print(f"rewrote {path}")


if __name__ == "__main__":
    main(sys.argv[1:] or ["."])
