"""A page section that may fail on its own: a missing, half-written or corrupt artifact shows a clear message in
the section it affects, and the rest of the page still renders.

    runs = section("runs", lambda: list_runs(store))       # Section(value=[...]) or Section(error="runs: ...")
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

import pyarrow as pa

from storage.errors import CorruptArtifactError, MissingInputError

logger = logging.getLogger(__name__)

T = TypeVar("T")

#: Errors a store can raise while being read (missing or half-written artifacts, corrupt files, bad schemas).
READ_ERRORS: tuple[type[BaseException], ...] = (OSError, ValueError, KeyError, CorruptArtifactError,
                                                 MissingInputError, pa.ArrowException)


@dataclass(frozen=True)
class Section(Generic[T]):
    """A section's content, or the message saying why it cannot be shown.

    Attributes:
        name: what the section shows ("runs", "reconstruction quality").
        value: its content (``None`` when ``error`` is set).
        error: the message naming the file or field at fault (``""``: none).
    """

    name: str
    value: T | None = None
    error: str = ""

    @property
    def ok(self) -> bool:
        return not self.error


def section(name: str, read: Callable[[], T]) -> Section[T]:
    """``read()`` as a section; a store read error becomes the section's message (and a warning in the log)."""
    try:
        return Section(name, value=read())
    except READ_ERRORS as exc:
        logger.warning("dashboard section %s: %s", name, exc)
        return Section(name, error=f"{name}: {exc}")
