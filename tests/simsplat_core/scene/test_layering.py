"""simsplat_core.scene and .eval are framework-free: no prefect, ray, storage or pyarrow imports."""

from __future__ import annotations

import subprocess
import sys


def test_scene_imports_no_framework_or_storage() -> None:
    code = (
        "import sys, simsplat_core.scene, simsplat_core.eval; "
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('prefect', 'ray', 'storage', 'tasks', 'flows', "
        "'pyarrow')); assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
