"""storage/ may import simsplat_core.types, never prefect or ray; simsplat_core never imports storage."""

from __future__ import annotations

import subprocess
import sys


def test_storage_imports_no_orchestration_framework() -> None:
    code = (
        "import sys, storage, simsplat_core.types; "
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('prefect', 'ray')); "
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
