"""A tiny reconstructed synthetic scene shared by the alignment tests (node masks, feature field, builder).

Seed 0 at 4 frames of 96x64 (frame 3 held out) has a red sedan (``veh_01``, ~1600 ground-truth pixels
over the 12 images) and a large white truck (``veh_03``); the graph is the depth initialisation of the training
frames (``scene.init.initial_graph``, what ``reconstruct`` starts from; about two seconds).
"""

from __future__ import annotations

import functools

from simsplat_core.scene import ReconstructionConfig, SceneGraph
from simsplat_core.scene.init import initial_graph
from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

TINY_SEED = 0
TINY_WORLD = WorldConfig(num_frames=4, width=96, height=64, test_every=4)


@functools.cache
def _tiny() -> tuple[SceneLog, SceneGraph]:
    log = generate_log(TINY_SEED, TINY_WORLD)
    config = ReconstructionConfig()
    graph = initial_graph(log, config.init, {img.frame_idx for img in log.images if img.split == "train"},
                          seed=config.seed).with_eps2d(config.eps2d)
    return log, graph


def tiny_log() -> SceneLog:
    return _tiny()[0]


def tiny_graph() -> SceneGraph:
    """A fresh copy of the tiny scene's graph (callers may change its features)."""
    return SceneGraph.from_records(_tiny()[1].to_records("tiny"))
