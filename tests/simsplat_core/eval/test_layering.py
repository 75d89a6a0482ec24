"""eval/ sits on top of the algorithms it measures: simsplat_core.language and .scene import nothing from it.

Checked twice: statically (no module of the package names ``simsplat_core.eval`` in an import statement)
and at run time (importing every module of the package loads no ``simsplat_core.eval`` module, which
also catches imports through other packages).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import simsplat_core

CORE = Path(simsplat_core.__file__).resolve().parent

#: Imports every module of a package, then fails naming the simsplat_core.eval modules that got loaded.
RUNTIME_CHECK = """
import importlib, pkgutil, sys
package = importlib.import_module({package!r})
for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
    importlib.import_module(info.name)
bad = sorted(m for m in sys.modules if m == "simsplat_core.eval" or m.startswith("simsplat_core.eval."))
assert not bad, bad
"""


def eval_imports(path: Path, root: Path = CORE) -> list[str]:
    """``file:line module`` (``file`` relative to ``root``) for every import statement of ``path`` that
    names ``simsplat_core.eval``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names = [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
        else:
            continue
        if any(n == "simsplat_core.eval" or n.startswith("simsplat_core.eval.") for n in names):
            found.append(f"{path.relative_to(root)}:{node.lineno} {names[0]}")
    return found


def test_eval_imports_finds_every_import_form(tmp_path: Path) -> None:
    module = tmp_path / "probe.py"
    module.write_text("import simsplat_core.eval.grounding.tables\nfrom simsplat_core import eval\n"
                      "from simsplat_core.eval.motion import split_objects\nfrom simsplat_core.evaluation import x\n")
    assert [hit.split(" ")[0] for hit in eval_imports(module, tmp_path)] == ["probe.py:1", "probe.py:2", "probe.py:3"]


@pytest.mark.parametrize("package", ["language", "scene"])
def test_no_module_names_eval(package: str) -> None:
    bad = [hit for path in sorted((CORE / package).rglob("*.py")) for hit in eval_imports(path)]
    assert not bad, bad


@pytest.mark.parametrize(
    "package",
    [
        "simsplat_core.language",
        "simsplat_core.scene",
    ],
)
def test_importing_the_package_loads_no_eval_module(package: str) -> None:
    code = RUNTIME_CHECK.format(package=package)
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-2000:]
