"""What every benchmark records beside its figures, and how it writes them: the machine it ran on, the load average
around a measurement (this machine's cores are shared, so a figure is read against the load it was taken under), and
the result as ``<out>/<name>.json``.

Imported by the benchmark scripts of this folder as ``run_info`` (a script's own folder is first on ``sys.path``).
"""

from __future__ import annotations

import json
import logging
import os
import platform
from pathlib import Path
from typing import Any

logger = logging.getLogger("bench.run_info")


def load_average() -> list[float]:
    """The 1/5/15-minute load averages (empty where the OS has none)."""
    return [round(v, 2) for v in os.getloadavg()] if hasattr(os, "getloadavg") else []


def machine_info() -> dict[str, Any]:
    """The CPU count, platform and Python version of this machine."""
    return {"cpus": os.cpu_count(), "platform": platform.platform(), "python": platform.python_version()}


def write_json_result(result: dict[str, Any], path: Path) -> Path:
    """Write ``result`` as indented JSON to ``path`` (its folder created; values JSON cannot hold written as text);
    returns ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=2, default=str) + "\n")
    logger.info("wrote %s", path)
    return path
