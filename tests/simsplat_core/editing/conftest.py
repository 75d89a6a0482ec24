"""Fixtures of the editing tests: a synthetic log without pixels, its initial (untrained) scene graph and a
ground-truth language scene whose node ids are the graph's."""

from __future__ import annotations

import dataclasses

import pytest

from simsplat_core.eval.grounding.gt_scene import language_scene_from_log
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import TextEncoder, default_text_encoder
from simsplat_core.scene import InitConfig, SceneGraph
from simsplat_core.scene.init import initial_graph
from simsplat_core.types import SceneLog
from simsplat_core.world import WorldConfig, generate_log

#: Seed of the edited world (the demo world: 10 vehicles incl. a white van, 8 pedestrians, 3 signs, 2 cones).
EDIT_SEED = 0


@pytest.fixture(scope="session")
def edit_log() -> SceneLog:
    return generate_log(EDIT_SEED, WorldConfig(num_frames=40, width=96, height=64, render_images=False))


@pytest.fixture(scope="session")
def edit_graph(edit_log: SceneLog) -> SceneGraph:
    """Random-cloud Gaussians (no images), one node per object, on the log's boxes."""
    return initial_graph(edit_log, InitConfig(), set(range(edit_log.num_frames)))


@pytest.fixture(scope="session")
def encoder() -> TextEncoder:
    return default_text_encoder()


@pytest.fixture(scope="session")
def edit_language(edit_log: SceneLog, edit_graph: SceneGraph, encoder: TextEncoder) -> LanguageScene:
    """Ground-truth captions and label-built motion features, renumbered to the graph's node ids."""
    scene = language_scene_from_log(edit_log, encoder, appearance="ground_truth")
    node_of = {n.object_id: n.node_id for n in edit_graph.object_nodes}
    nodes = tuple(sorted((dataclasses.replace(n, node_id=node_of[n.object_id]) for n in scene.nodes),
                         key=lambda n: n.node_id))
    return dataclasses.replace(scene, nodes=nodes)


@pytest.fixture(scope="session")
def engine(encoder: TextEncoder) -> QueryEngine:
    return QueryEngine(encoder)
