"""The version of the code that made an artifact: ``git describe`` of the checkout, else the installed package's;
and ``source_digest``, the digest of the modules whose code determines a cached result."""

from __future__ import annotations

import hashlib
import logging
import subprocess
from importlib import metadata
from pathlib import Path
from types import ModuleType

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


def source_digest(*modules: ModuleType) -> str:
    """A digest of the source text of ``modules`` (in the order given; a package counts with every ``.py`` file
    under it): a cache whose rows these modules compute stamps it, so editing any of them invalidates the cache.

    Raises:
        ValueError: a module has no readable source file (named).
    """
    if not modules:
        raise ValueError("source_digest: no modules given")
    digest = hashlib.sha256()
    for module in modules:
        path = getattr(module, "__file__", None)
        if not path:
            raise ValueError(f"source_digest: module {module.__name__} has no source file")
        files = sorted(Path(path).parent.rglob("*.py")) if hasattr(module, "__path__") else [Path(path)]
        for file in files:
            digest.update(f"{module.__name__}:{file.name}".encode())
            digest.update(file.read_bytes())
    return digest.hexdigest()[:16]
