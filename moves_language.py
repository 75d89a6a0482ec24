"""Rewrite imports and mentions of the language / mining modules this branch moved.

    python3 moves_language.py simsplat_core storage tasks flows tests bench docs README.md pyproject.toml

Every ``.py`` / ``.md`` / ``.toml`` file under the given paths is rewritten in place:

1. symbols that moved to another module (``SYMBOL_MOVES``): ``from OLD import a, Moved, b`` becomes
   ``from OLD import a, b`` plus ``from NEW import Moved`` (single-line and parenthesised imports, at any
   indentation);
2. modules that moved (``MODULE_MOVES``): dotted paths (``simsplat_core.language.query_parse``, also inside
   longer paths and strings) and file paths (``simsplat_core/language/query_parse.py``);
3. ``from simsplat_core.language import query_lexicon`` (a moved module imported from its parent) becomes
   ``from simsplat_core.language.grounding import lexicon as query_lexicon``;
4. short mentions in docstrings and comments: ``language.query_parse`` -> ``language.grounding.parse`` (every
   moved language module), and ````query_parse.find_spans```` -> ````grounding.parse.find_spans```` (the
   ``query_*`` modules named in double backticks).

Run ``ruff check --fix`` afterwards: split imports may need re-sorting. Idempotent.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

LANG = "simsplat_core.language"

#: old dotted module -> new dotted module (tests included, so path mentions in docs follow).
MODULE_MOVES: dict[str, str] = {
    f"{LANG}.scene_builder": f"{LANG}.alignment.scene_builder",
    f"{LANG}.feature_field": f"{LANG}.alignment.feature_field",
    f"{LANG}.motion_encoder": f"{LANG}.alignment.motion_encoder",
    f"{LANG}.motion_dataset": f"{LANG}.alignment.motion_dataset",
    f"{LANG}.motion_training": f"{LANG}.alignment.motion_training",
    f"{LANG}.query": f"{LANG}.grounding.engine",
    f"{LANG}.query_config": f"{LANG}.grounding.config",
    f"{LANG}.query_lexicon": f"{LANG}.grounding.lexicon",
    f"{LANG}.query_messages": f"{LANG}.grounding.messages",
    f"{LANG}.query_parse": f"{LANG}.grounding.parse",
    f"{LANG}.query_result": f"{LANG}.grounding.result",
    f"{LANG}.query_scoring": f"{LANG}.grounding.scoring",
    f"{LANG}.static_location": f"{LANG}.grounding.static_location",
    "tests.simsplat_core.language.test_feature_field": "tests.simsplat_core.language.alignment.test_feature_field",
    "tests.simsplat_core.language.test_motion_alignment":
        "tests.simsplat_core.language.alignment.test_motion_alignment",
    "tests.simsplat_core.language.test_scene_builder": "tests.simsplat_core.language.alignment.test_scene_builder",
    "tests.simsplat_core.language.test_query": "tests.simsplat_core.language.grounding.test_engine",
    "tests.simsplat_core.language.test_query_parse": "tests.simsplat_core.language.grounding.test_parse",
    "tests.simsplat_core.language.test_static_location":
        "tests.simsplat_core.language.grounding.test_static_location",
    "tests.simsplat_core.language.look_alikes": "tests.simsplat_core.language.grounding.look_alikes",
}

#: (old module, symbol) -> new module; applied before ``MODULE_MOVES`` (keys use the old module paths).
SYMBOL_MOVES: dict[tuple[str, str], str] = {
    (f"{LANG}.motion_training", "ObjectMotionFeatures"): f"{LANG}.scene_language",
    **{("simsplat_core.mining.scene_facts", name): "simsplat_core.mining.scene_fact_records"
       for name in ("AREAS", "ONCOMING_DEG", "AgentFacts", "AssetFacts", "RoadFacts", "SceneFacts")},
}

SUFFIXES = (".py", ".md", ".toml")


def _names(body: str) -> list[str]:
    """The imported names of an import list (``a``, ``b as c``), comments dropped."""
    body = re.sub(r"#[^\n]*", "", body)
    return [n.strip() for n in body.replace("\n", " ").split(",") if n.strip()]


def _import_lines(indent: str, module: str, names: list[str], comment: str) -> str:
    line = f"{indent}from {module} import {', '.join(names)}{comment}"
    if len(line) <= 120:
        return line
    inner = "".join(f"{indent}    {n},\n" for n in names)
    return f"{indent}from {module} import ({comment}\n{inner}{indent})"


def move_symbols(text: str) -> str:
    """Step 1 of the module docstring."""
    for old in sorted({m for m, _ in SYMBOL_MOVES}):
        rx = re.compile(r"^(?P<indent>[ \t]*)from " + re.escape(old)
                        + r" import (?:\((?P<paren>[^)]*)\)|(?P<line>[^\n(]*?))(?P<comment>[ \t]*#[^\n]*)?$",
                        re.MULTILINE)

        def repl(m: re.Match[str], old: str = old) -> str:
            names = _names(m.group("paren") if m.group("paren") is not None else m.group("line"))
            comment = m.group("comment") or ""
            groups: dict[str, list[str]] = {}
            for name in names:
                target = SYMBOL_MOVES.get((old, name.split(" as ")[0].strip()), old)
                groups.setdefault(target, []).append(name)
            if list(groups) == [old]:
                return m.group(0)
            indent = m.group("indent")
            return "\n".join(_import_lines(indent, module, group, comment if i == 0 else "")
                             for i, (module, group) in enumerate(groups.items()))

        text = rx.sub(repl, text)
    return text


def move_modules(text: str) -> str:
    """Steps 2 and 3 of the module docstring."""
    for old, new in MODULE_MOVES.items():
        parent, _, leaf = old.rpartition(".")
        new_parent, _, new_leaf = new.rpartition(".")
        alias = "" if leaf == new_leaf else f" as {leaf}"
        text = re.sub(rf"^([ \t]*)from {re.escape(parent)} import {leaf}[ \t]*$",
                      rf"\1from {new_parent} import {new_leaf}{alias}", text, flags=re.MULTILINE)
        text = re.sub(r"(?<![\w.])" + re.escape(old) + r"(?![\w])", new, text)
        text = re.sub(r"(?<![\w/])" + re.escape(old.replace(".", "/")) + r"(?=\.py\b|/)",
                      new.replace(".", "/"), text)
        if old.startswith(LANG + "."):
            short_old, short_new = old[len("simsplat_core."):], new[len("simsplat_core."):]
            text = re.sub(r"(?<![\w.])" + re.escape(short_old) + r"(?![\w])", short_new, text)
    text = re.sub(r"(?<=``)query_(parse|lexicon|scoring|config|messages|result)(?=[.`])", r"grounding.\1", text)
    return text


def rewrite(path: Path) -> bool:
    text = path.read_text()
    new = move_modules(move_symbols(text)) if path.suffix == ".py" else move_modules(text)
    if new != text:
        path.write_text(new)
        return True
    return False


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__)
        return 2
    changed = 0
    for arg in argv:
        root = Path(arg)
        files = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.suffix in SUFFIXES)
        for path in files:
            if path.suffix in SUFFIXES and path.name != "moves_language.py" and rewrite(path):
                print(f"rewrote {path}")
                changed += 1
    print(f"{changed} files rewritten")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
