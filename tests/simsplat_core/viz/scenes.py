"""Agents for the bird's-eye-view tests: straight eastbound paths at 10 m/s, 10 steps a second."""

from __future__ import annotations

import numpy as np

from simsplat_core.scenario.agents import AgentStates

T = 20
CAR = (4.5, 1.9, 1.6)


def straight_agents(ids: tuple[str, ...], sources: tuple[str, ...], starts: list[tuple[float, float]],
                    categories: tuple[str, ...] | None = None, step_m: float = 1.0) -> AgentStates:
    """Agent ``k`` starts at ``starts[k]`` and moves ``step_m`` along +x per step (heading 0), car-sized."""
    n = len(ids)
    t = np.arange(T)
    xy = np.stack([np.stack([x0 + step_m * t, np.full(T, y0)], -1) for x0, y0 in starts])
    return AgentStates(object_ids=ids, categories=categories or ("vehicle",) * n, sources=sources,
                       node_ids=np.arange(n) - 1, frame_idx=t, times=t / 10.0, xy=xy, z=np.full((n, T), 0.8),
                       heading=np.zeros((n, T)), speed=np.full((n, T), step_m * 10.0), size=np.tile(CAR, (n, 1)),
                       valid=np.ones((n, T), bool))


def color_mask(image: np.ndarray, color: tuple[int, ...]) -> np.ndarray:
    """``[H, W]`` bool: pixels of exactly ``color``."""
    return np.all(image == np.array(color, np.uint8), axis=-1)


def assert_tinted(pixel: np.ndarray, color: tuple[int, int, int], background: float) -> None:
    """``pixel [3]`` is ``color`` anti-aliased over a grey ``background``: ``background + alpha (color -
    background)`` with most of the colour (``alpha > 0.5``)."""
    got = np.asarray(pixel, float) - background
    want = np.asarray(color, float) - background
    alpha = got @ want / (want @ want)
    assert alpha > 0.5 and np.abs(got - alpha * want).max() < 6.0, (pixel, color)
