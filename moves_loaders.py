"""Rewrite mentions of modules this branch renamed, in place: ``python moves_loaders.py DIR [DIR ...]``.

Renamed: ``simsplat_core.data.feather_io`` -> ``simsplat_core.data.arrow_columns`` (it reads Parquet too).
Rewrites dotted paths (``from X import``, ``import X``, strings) and file paths in .py/.md/.toml files.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

logger = logging.getLogger(__name__)

MOVES = {
    "simsplat_core.data.feather_io": "simsplat_core.data.arrow_columns",
    "simsplat_core/data/feather_io.py": "simsplat_core/data/arrow_columns.py",
}


def rewrite(path: Path) -> bool:
    """Apply ``MOVES`` to one file; True when it changed."""
    text = path.read_text(encoding="utf-8")
    new = text
    for old, replacement in MOVES.items():
        new = new.replace(old, replacement)
    if new != text:
        path.write_text(new, encoding="utf-8")
    return new != text


def main(folders: list[str]) -> None:
    for folder in folders:
        for path in sorted(Path(folder).rglob("*")):
            if path.suffix not in {".py", ".md", ".toml"} or ".venv" in path.parts or path.name == Path(__file__).name:
                continue
            if rewrite(path):
                logger.info("rewrote %s", path)


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(sys.argv[1:] or ["."])
