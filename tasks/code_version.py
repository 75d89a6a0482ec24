"""The version of the code that made an artifact: ``git describe`` of the checkout, else the installed package's."""

from __future__ import annotations

import logging
import subprocess
from importlib import metadata
from pathlib import Path

logger = logging.getLogger(__name__)


def code_version(root: Path | None = None) -> str:
    """``git describe --always --dirty`` of the checkout holding this code, else the installed package's version."""
    where = root or Path(__file__).resolve().parents[1]
    try:
        done = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=where, capture_output=True, text=True,
                              timeout=10, check=False)
        if done.returncode == 0 and done.stdout.strip():
            return done.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        logger.debug("git describe failed in %s", where, exc_info=True)
    try:
        return metadata.version("simsplat")
    except metadata.PackageNotFoundError:
        return "unknown"
