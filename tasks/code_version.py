"""The version of the code that made an artifact: ``git describe`` of the checkout, else the installed package's; and
a digest of the source of given modules (``source_digest``) for results cached across runs."""

from __future__ import annotations

import hashlib
import importlib.util
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


def source_digest(*modules: str) -> str:
    """A digest of the Python source of ``modules`` (dotted names; a package counts with every module below it).

    Results cached across runs carry it in their key, so that a change to the code that computes them invalidates
    them, whether or not the checkout is a git repository.

    Raises:
        ModuleNotFoundError: a name that does not import.
    """
    digest = hashlib.sha256()
    for name in sorted(modules):
        spec = importlib.util.find_spec(name)
        if spec is None or spec.origin is None:
            raise ModuleNotFoundError(f"source_digest: no module {name!r}")
        origin = Path(spec.origin)
        files = sorted(origin.parent.rglob("*.py")) if origin.name == "__init__.py" else [origin]
        for path in files:
            digest.update(str(path.relative_to(origin.parent)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]
