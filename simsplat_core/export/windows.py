"""Fixed-length windows at a fixed rate cut from a log of any length and rate (WOMD's 91 steps at 10 Hz).

A log whose frames are already at the layout's rate (every frame gap within ``rate_tolerance`` of the period:
Waymo's ~0.1 s steps jitter by milliseconds) keeps its own frames and timestamps, so nothing is interpolated.
Another rate is resampled onto a uniform grid from the first frame, by linear interpolation between the two
frames around each grid time (headings along the shorter arc); a grid step is valid when both frames are.
Windows start at grid step 0 and every ``stride`` steps until one reaches the last step, so no step of the log
is dropped; the last window (or the only one, of a short log) is padded with invalid steps at the layout's
rate. The default stride is the future horizon (``steps - current_index - 1``): consecutive windows overlap by
the history, and each step is in the future of exactly one window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.scenario.agents import AgentStates


@dataclass(frozen=True)
class ExportLayout:
    """Length, rate and stride of exported scenarios.

    Attributes:
        steps: steps per scenario (WOMD: 91).
        current_index: the last history step (WOMD: 10).
        hz: steps per second (WOMD: 10).
        stride: steps between window starts; ``None``: the future horizon (module docstring).
        rate_tolerance: a log is at the layout's rate when every frame gap is within this fraction of the period.
    """

    steps: int = 91
    current_index: int = 10
    hz: float = 10.0
    stride: int | None = None
    rate_tolerance: float = 0.1

    def __post_init__(self) -> None:
        if self.steps < 1 or not 0 <= self.current_index < self.steps:
            raise ValueError(f"ExportLayout: current_index {self.current_index} must be a step of {self.steps}")
        if self.hz <= 0:
            raise ValueError(f"ExportLayout.hz must be positive, got {self.hz}")
        if self.stride is not None and self.stride < 1:
            raise ValueError(f"ExportLayout.stride must be at least 1, got {self.stride}")

    @property
    def window_stride(self) -> int:
        return self.stride if self.stride is not None else max(self.steps - self.current_index - 1, 1)


@dataclass(frozen=True)
class Window:
    """One window of a log.

    Attributes:
        index: 0, 1, ... in time order.
        times: ``[steps]`` seconds since the log's first frame.
        source: ``[steps]`` fractional frame index of the log at each step, NaN where the window is padded.
    """

    index: int
    times: np.ndarray
    source: np.ndarray

    @property
    def padded_steps(self) -> int:
        return int(np.isnan(self.source).sum())


@dataclass(frozen=True)
class WindowPlan:
    """The windows of a log and what was done to fit the layout (notes for the manifest)."""

    windows: tuple[Window, ...]
    resampled: bool
    notes: tuple[str, ...]


def at_layout_rate(times: np.ndarray, layout: ExportLayout) -> bool:
    """Whether every gap of ``times`` ``[T]`` (seconds) is within the layout's tolerance of its period."""
    gaps = np.diff(np.asarray(times, np.float64))
    period = 1.0 / layout.hz
    return bool(np.all(np.abs(gaps - period) <= layout.rate_tolerance * period))


def plan_windows(times: np.ndarray, layout: ExportLayout) -> WindowPlan:
    """The windows of a log whose frames are at ``times`` ``[T]`` seconds (increasing; module docstring)."""
    times = np.asarray(times, np.float64)
    if times.size == 0:
        raise ValueError("plan_windows: the log has no frames")
    period = 1.0 / layout.hz
    notes: list[str] = []
    resampled = not at_layout_rate(times, layout)
    if resampled:
        grid = times[0] + np.arange(int(np.floor((times[-1] - times[0]) / period + 1e-9)) + 1) * period
        source = np.interp(grid, times, np.arange(times.size, dtype=np.float64))
        rate = (times.size - 1) / max(times[-1] - times[0], 1e-9)
        notes.append(f"resampled from {rate:.2f} Hz to {layout.hz:g} Hz by linear interpolation")
    else:
        grid, source = times, np.arange(times.size, dtype=np.float64)
    starts = [0]
    while starts[-1] + layout.steps < grid.size:
        starts.append(starts[-1] + layout.window_stride)
    windows = []
    for k, start in enumerate(starts):
        take = np.arange(start, start + layout.steps)
        inside = take < grid.size
        last = grid[-1]
        w_times = np.where(inside, grid[np.minimum(take, grid.size - 1)], last + (take - grid.size + 1) * period)
        w_source = np.where(inside, source[np.minimum(take, grid.size - 1)], np.nan)
        windows.append(Window(k, w_times, w_source))
    if len(windows) > 1:
        notes.append(f"{grid.size} steps cut into {len(windows)} windows of {layout.steps} "
                     f"(stride {layout.window_stride})")
    padded = windows[-1].padded_steps
    if padded:
        notes.append(f"last window padded with {padded} invalid steps")
    return WindowPlan(tuple(windows), resampled, tuple(notes))


@dataclass(frozen=True)
class SampledStates:
    """Agent states sampled at a window's steps (``A`` agents, ``S`` steps).

    Attributes:
        xy: ``[A, S, 2]``; z, heading, speed: ``[A, S]``; valid: ``[A, S]`` bool (False at padded steps).
    """

    xy: np.ndarray
    z: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    valid: np.ndarray


def sample_states(states: AgentStates, source: np.ndarray) -> SampledStates:
    """``states`` at fractional frame indices ``source`` ``[S]`` (NaN: padded, invalid; module docstring)."""
    source = np.asarray(source, np.float64)
    padded = np.isnan(source)
    pos = np.where(padded, 0.0, source)
    lo = np.clip(np.floor(pos).astype(np.int64), 0, states.num_steps - 1)
    hi = np.clip(lo + 1, 0, states.num_steps - 1)
    w = np.clip(pos - lo, 0.0, 1.0)
    hi = np.where(w > 0, hi, lo)

    def lerp(values: np.ndarray) -> np.ndarray:
        a, b = values[:, lo], values[:, hi]
        ww = w.reshape((1, -1) + (1,) * (values.ndim - 2))
        return a + (b - a) * ww

    heading = states.heading[:, lo] + wrap_angle(states.heading[:, hi] - states.heading[:, lo]) * w[None]
    valid = states.valid[:, lo] & states.valid[:, hi] & ~padded[None]
    return SampledStates(xy=lerp(states.xy), z=lerp(states.z), heading=wrap_angle(heading),
                         speed=lerp(states.speed), valid=valid)
