"""Rewrite mentions of the old flat ``simsplat_core.editing`` modules to their subpackage paths.

    python3 moves_editing.py simsplat_core storage tasks flows tests bench docs README.md

Rewrites, in place, in every ``.py`` / ``.md`` / ``.toml`` file under the given directories (or the given files):

* ``from simsplat_core.editing.OLD import ...`` / ``import simsplat_core.editing.OLD`` and every other dotted
  mention ``simsplat_core.editing.OLD[.attr]`` (strings, docstrings, docs);
* ``from simsplat_core.editing import OLD [as alias]`` -> ``from simsplat_core.editing.PKG import NEW as alias``;
* file paths ``simsplat_core/editing/OLD.py`` and test paths ``tests/simsplat_core/editing/OLD.py``;
* short mentions ``editing.OLD`` (docstrings, comments) and bare distinctive module names in double backticks
  (````parser_chunks.split_clauses```` -> ````editing.parse.chunks.split_clauses````).

* ``EditContext`` (was ``editing.apply``) and ``Draft`` (was ``editing.edit_ops``) imported from ``editing.draft``.

Imports it splits may need re-sorting: run ``ruff check --fix --select I`` on the same paths afterwards.
Running it twice changes nothing more: a mention already naming a new module is left alone.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

#: Old module (relative to ``simsplat_core.editing``) -> new module (relative to the same package).
MOVES: dict[str, str] = {
    # the prompt parser
    "parser": "parse.prompt",
    "parser_anchor": "parse.anchor",
    "parser_behaviour": "parse.behaviour",
    "parser_chunks": "parse.chunks",
    "parser_clauses": "parse.clauses",
    "parser_lexicon": "parse.lexicon",
    "parser_placement": "parse.placement",
    "parser_predicate": "parse.predicate",
    "parser_semantic": "parse.semantic",
    "parser_speed": "parse.speed",
    "parser_state": "parse.state",
    "parser_text": "parse.text",
    # the asset bank
    "assets": "assets.bank",
    "asset_colors": "assets.colors",
    "asset_cutout": "assets.cutout",
    "asset_nodes": "assets.nodes",
    "asset_quality": "assets.quality",
    "asset_record": "assets.record",
    "asset_render": "assets.render",
    "procedural_assets": "assets.procedural",
    "look_check": "assets.look_check",
    # the motion controller
    "motion_controller": "motion.controller",
    "motion_glue": "motion.plans",
    "motion_requests": "motion.requests",
    "motion_routes": "motion.routes",
    "speed_profile": "motion.speed_profile",
    "merge_gap": "motion.merge_gap",
    "joining": "motion.joining",
    # the placement resolver
    "placement": "placement.resolve",
    "placement_areas": "placement.areas",
    # the traffic's reaction to an edit
    "reaction": "traffic.reaction",
    "room": "traffic.room",
    # the edit ops
    "edit_ops": "ops",
}

#: Test modules (relative to ``tests.simsplat_core.editing``) -> their new place.
TEST_MOVES: dict[str, str] = {
    "asset_fixtures": "assets.fixtures",
    "test_asset_cutout": "assets.test_cutout",
    "test_asset_nodes": "assets.test_nodes",
    "test_assets": "assets.test_bank",
    "test_look_check": "assets.test_look_check",
    "test_procedural_assets": "assets.test_procedural",
    "heldout_prompts": "parse.heldout_prompts",
    "parser_checks": "parse.parser_checks",
    "test_parser": "parse.test_parser",
    "test_parser_heldout": "parse.test_heldout",
    "test_merge_gap": "motion.test_merge_gap",
    "test_motion_controller": "motion.test_controller",
    "test_placement": "placement.test_resolve",
}

#: Names that moved to another module (after the module moves above): module -> {name: new module}.
SYMBOL_MOVES: dict[str, dict[str, str]] = {
    "simsplat_core.editing.apply": {"EditContext": "simsplat_core.editing.draft"},
    "simsplat_core.editing.ops": {"Draft": "simsplat_core.editing.draft",
                                  "INSERTED_PREFIX": "simsplat_core.editing.draft"},
}

#: Old names distinctive enough to rewrite when they stand bare in double backticks.
DISTINCTIVE = {m for m in MOVES if "_" in m and MOVES[m].rpartition(".")[2] != m}

SUFFIXES = (".py", ".md", ".toml")


def _new_modules(moves: dict[str, str]) -> set[str]:
    return set(moves.values())


def _dotted(text: str, base: str, moves: dict[str, str], lookbehind: str) -> str:
    """``base.OLD`` -> ``base.NEW`` wherever ``OLD`` is a whole module name not already followed by a new leaf."""
    news = _new_modules(moves)
    names = "|".join(sorted((re.escape(o) for o in moves), key=len, reverse=True))
    pattern = re.compile(rf"{lookbehind}{re.escape(base)}\.({names})(?![\w])")

    def sub(m: re.Match[str]) -> str:
        old = m.group(1)
        follow = re.match(r"\.(\w+)", text[m.end():])
        if follow and f"{old}.{follow.group(1)}" in news:
            return m.group(0)  # already a new module path
        return m.group(0)[: -len(old)] + moves[old]

    return pattern.sub(sub, text)


def _from_package(text: str, base: str, moves: dict[str, str]) -> str:
    """``from base import OLD [as alias]`` -> ``from base.PKG import NEW [as alias]``."""
    pattern = re.compile(rf"^(\s*)from {re.escape(base)} import (\w+)(?: as (\w+))?[ \t]*$", re.M)

    def sub(m: re.Match[str]) -> str:
        old, alias = m.group(2), m.group(3)
        if old not in moves:
            return m.group(0)
        parent, _, leaf = f"{base}.{moves[old]}".rpartition(".")
        name = alias or old
        return f"{m.group(1)}from {parent} import {leaf}" + ("" if name == leaf else f" as {name}")

    return pattern.sub(sub, text)


def _paths(text: str, base: str, moves: dict[str, str]) -> str:
    """``base/OLD.py`` -> ``base/NEW/PATH.py``."""
    names = "|".join(sorted((re.escape(o) for o in moves), key=len, reverse=True))
    pattern = re.compile(rf"(?<![\w/]){re.escape(base)}/({names})\.py\b")
    return pattern.sub(lambda m: f"{base}/{moves[m.group(1)].replace('.', '/')}.py", text)


def _backticked(text: str) -> str:
    """````OLD[.attr]```` (a distinctive old name alone) -> ````editing.NEW[.attr]````."""
    names = "|".join(sorted((re.escape(o) for o in DISTINCTIVE), key=len, reverse=True))
    pattern = re.compile(rf"``({names})((?:\.\w+)*)``")
    return pattern.sub(lambda m: f"``editing.{MOVES[m.group(1)]}{m.group(2)}``", text)


def _symbols(text: str) -> str:
    """``from MOD import a, Moved, b`` -> ``from MOD import a, b`` plus ``from NEW import Moved``; dotted mentions
    ``MOD.Moved`` -> ``NEW.Moved`` (also the short ``editing.`` forms)."""
    for module, moved in SYMBOL_MOVES.items():
        pattern = re.compile(rf"^([ \t]*)from {re.escape(module)} import (\(([^)]*)\)|[^\n(]+)$", re.M)

        def sub(m: re.Match[str], moved: dict[str, str] = moved, module: str = module) -> str:
            indent, body = m.group(1), m.group(3) if m.group(3) is not None else m.group(2)
            names = [n.strip() for n in body.replace("\n", " ").split(",") if n.strip()]
            kept = [n for n in names if n.split(" as ")[0] not in moved]
            if len(kept) == len(names):
                return m.group(0)
            lines = [f"{indent}from {module} import {', '.join(kept)}"] if kept else []
            targets: dict[str, list[str]] = {}
            for n in names:
                if n.split(" as ")[0] in moved:
                    targets.setdefault(moved[n.split(" as ")[0]], []).append(n)
            lines += [f"{indent}from {new} import {', '.join(ns)}" for new, ns in targets.items()]
            return "\n".join(lines)

        text = pattern.sub(sub, text)
        for name, new in moved.items():
            text = re.sub(rf"(?<![\w.]){re.escape(module)}\.{name}\b", f"{new}.{name}", text)
            short_old, short_new = module.removeprefix("simsplat_core."), new.removeprefix("simsplat_core.")
            text = re.sub(rf"(?<![\w.]){re.escape(short_old)}\.{name}\b", f"{short_new}.{name}", text)
    return text


def rewrite(text: str) -> str:
    """Every rewrite of the module docstring on one file's text."""
    text = _from_package(text, "simsplat_core.editing", MOVES)
    text = _from_package(text, "tests.simsplat_core.editing", TEST_MOVES)
    text = _dotted(text, "tests.simsplat_core.editing", TEST_MOVES, r"(?<![\w.])")
    text = _dotted(text, "simsplat_core.editing", MOVES, r"(?<![\w.])")
    text = _dotted(text, "editing", MOVES, r"(?<![\w.])")
    text = _paths(text, "tests/simsplat_core/editing", TEST_MOVES)
    text = _paths(text, "simsplat_core/editing", MOVES)
    return _symbols(_backticked(text))


def files(args: list[str]) -> list[Path]:
    out: list[Path] = []
    for arg in args:
        path = Path(arg)
        if path.is_file():
            out.append(path)
        else:
            out.extend(p for p in sorted(path.rglob("*")) if p.suffix in SUFFIXES and p.is_file()
                       and ".venv" not in p.parts and ".git" not in p.parts and p.name != "moves_editing.py")
    return out


def main(args: list[str]) -> int:
    if not args:
        print(__doc__, file=sys.stderr)
        return 2
    changed = 0
    for path in files(args):
        text = path.read_text(encoding="utf-8")
        new = rewrite(text)
        if new != text:
            path.write_text(new, encoding="utf-8")
            changed += 1
            print(f"rewrote {path}")
    print(f"{changed} file(s) rewritten", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
