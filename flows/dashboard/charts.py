"""Line charts drawn as inline SVG by the server: the geometry of a trend (one line per series, one point per
run), which ``templates/charts.html`` turns into markup. No script and no outside library.

    chart = line_chart(trend.runs, trend.series)       # series: anything with .label and .values
    # chart.lines[k].points: ((x_px, y_px, value, run), ...); chart.y_ticks: ((y_px, "0.95"), ...)
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

#: Line colours, in series order (colour-blind safe, Okabe-Ito).
PALETTE: tuple[str, ...] = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000", "#f0e442")


#: Runs along the x axis that get a label at most (every k-th run beyond).
MAX_X_LABELS = 8
_STAMP = re.compile(r"(\d{4})(\d{2})(\d{2})T(\d{2})(\d{2})")


class Series(Protocol):
    """A line: its label and one value per run (``None``: no value)."""

    @property
    def label(self) -> str: ...

    @property
    def values(self) -> Sequence[float | None]: ...


def run_label(run_id: str) -> str:
    """A short x label of a run: ``MM-DD HH:MM`` of the time stamp in its id, else the id (at most 14 characters)."""
    stamp = _STAMP.search(run_id)
    if stamp:
        _, month, day, hour, minute = stamp.groups()
        return f"{month}-{day} {hour}:{minute}"
    return run_id if len(run_id) <= 14 else run_id[:13] + "…"


@dataclass(frozen=True)
class ChartPoint:
    """One value of a series: pixel position, the value and the run (x label) it belongs to."""

    x: float
    y: float
    value: float
    run: str


@dataclass(frozen=True)
class ChartLine:
    """One series: its label, colour, SVG ``points`` attribute of its polyline(s) and its points."""

    label: str
    color: str
    segments: tuple[str, ...]
    points: tuple[ChartPoint, ...]


@dataclass(frozen=True)
class LineChart:
    """A chart's geometry in pixels: size, the plot area's left/top/right/bottom, ticks and lines."""

    width: int
    height: int
    left: float
    top: float
    right: float
    bottom: float
    x_ticks: tuple[tuple[float, str], ...]
    y_ticks: tuple[tuple[float, str], ...]
    lines: tuple[ChartLine, ...]


def _nice_range(values: Sequence[float]) -> tuple[float, float]:
    """A y range covering ``values`` with a little margin (a flat series gets a band around its value)."""
    low, high = min(values), max(values)
    if math.isclose(low, high, rel_tol=1e-9, abs_tol=1e-12):
        pad = abs(low) * 0.05 or 0.5
        return low - pad, high + pad
    pad = (high - low) * 0.08
    return low - pad, high + pad


def _tick_label(value: float, span: float) -> str:
    digits = max(0, min(4, 2 - int(math.floor(math.log10(span))) if span > 0 else 2))
    return f"{value:.{digits}f}"


def line_chart(runs: Sequence[str], series: Sequence[Series], *, width: int = 520, height: int = 220,
               y_ticks: int = 4, unit: str = "") -> LineChart:
    """The geometry of a line chart: ``runs`` along x (in order), each series' values (``None``: no value, which
    breaks its line) along y; a ``unit`` of ``"share"`` keeps the y axis inside ``[0, 1]``. Raises ``ValueError``
    when a series' length differs from ``len(runs)``."""
    for line in series:
        if len(line.values) != len(runs):
            raise ValueError(f"series {line.label!r} has {len(line.values)} values for {len(runs)} runs")
    left, top, right, bottom = 52.0, 12.0, float(width - 40), float(height - 34)
    present = [v for line in series for v in line.values if v is not None]
    low, high = _nice_range(present) if present else (0.0, 1.0)
    if unit == "share":
        low, high = max(low, 0.0), min(high, 1.0)

    def x_of(k: int) -> float:
        return (left + right) / 2 if len(runs) == 1 else left + (right - left) * k / (len(runs) - 1)

    def y_of(v: float) -> float:
        return bottom - (bottom - top) * (v - low) / (high - low)

    lines = []
    for s, line in enumerate(series):
        label, values = line.label, line.values
        points = tuple(ChartPoint(round(x_of(k), 1), round(y_of(v), 1), v, runs[k])
                       for k, v in enumerate(values) if v is not None)
        segments: list[list[str]] = []
        current: list[str] = []
        for k, v in enumerate(values):
            if v is None:
                segments.append(current)
                current = []
            else:
                current.append(f"{x_of(k):.1f},{y_of(v):.1f}")
        segments.append(current)
        lines.append(ChartLine(label, PALETTE[s % len(PALETTE)], tuple(" ".join(c) for c in segments if len(c) > 1),
                               points))
    ticks = tuple((round(y_of(low + (high - low) * i / y_ticks), 1), _tick_label(low + (high - low) * i / y_ticks,
                                                                                  high - low))
                  for i in range(y_ticks + 1))
    every = math.ceil(len(runs) / MAX_X_LABELS) if runs else 1
    x_ticks = tuple((round(x_of(k), 1), run_label(run)) for k, run in enumerate(runs) if k % every == 0)
    return LineChart(width, height, left, top, right, bottom, x_ticks, ticks, tuple(lines))


__all__ = ["ChartLine", "ChartPoint", "LineChart", "PALETTE", "Series", "line_chart", "run_label"]
