"""Wall seconds per named stage, nested stages counted once (exclusive time).

    clock = StageClock()
    with clock.stage("apply"):
        ...
        with clock.stage("ground"):      # nested: its seconds go to "ground" and are not counted in "apply"
            ...
    clock.seconds                        # {"ground": 0.2, "apply": 0.5}

Timings are recorded, never read by an algorithm: code that takes a clock decides nothing from it.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from dataclasses import dataclass, field


@dataclass
class StageClock:
    """Accumulates wall seconds per stage name (``seconds``); a stage entered inside another is subtracted from the
    outer one, so the values add up to the wall time spent inside the outermost stages."""

    seconds: dict[str, float] = field(default_factory=dict)
    _open: list[list[float]] = field(default_factory=list, repr=False)  # per open stage: [children's seconds]

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        """Time the block as ``name`` (exclusive of stages nested in it)."""
        started = time.perf_counter()
        self._open.append([0.0])
        try:
            yield
        finally:
            elapsed = time.perf_counter() - started
            children = self._open.pop()[0]
            self.seconds[name] = self.seconds.get(name, 0.0) + max(elapsed - children, 0.0)
            if self._open:
                self._open[-1][0] += elapsed


def maybe_stage(clock: StageClock | None, name: str) -> AbstractContextManager[None]:
    """``clock.stage(name)``, or a no-op without a clock."""
    return clock.stage(name) if clock is not None else nullcontext()


__all__ = ["StageClock", "maybe_stage"]
