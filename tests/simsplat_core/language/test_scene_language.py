"""LanguageScene of an edited graph: node-id maps re-rendered or marked invalid, never silently stale."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.language.node_masks import render_node_id_maps
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage, StaleSceneError
from simsplat_core.scene import SceneGraph
from simsplat_core.types import SceneLog
from tests.simsplat_core.language.alignment_fixtures import tiny_graph, tiny_log


def _bare(node_id: int, object_id: str, category: str) -> NodeLanguage:
    return NodeLanguage(node_id, object_id, category, "", None, None, None)


@pytest.fixture(scope="module")
def setup() -> tuple[SceneLog, SceneGraph, LanguageScene]:
    log, graph = tiny_log(), tiny_graph()
    maps = render_node_id_maps(graph, log)
    nodes = tuple(_bare(n.node_id, n.object_id, n.category) for n in graph.object_nodes)
    scene = LanguageScene(log.seq_id, "", nodes, maps.frame_indices, maps.cameras, maps.maps, "e5")
    return log, graph, scene


def _visible_node(scene: LanguageScene) -> int:
    ids, counts = np.unique(scene.node_id_maps, return_counts=True)
    return int(max((c, i) for i, c in zip(ids, counts) if i > 0)[1])


def test_a_stored_scene_matches_its_graph(setup) -> None:
    _, graph, scene = setup
    scene.check_graph(graph)
    assert scene.maps_valid and scene.masks([_visible_node(scene)]).any()


def test_removal_without_the_log_invalidates_the_maps(setup) -> None:
    _, graph, scene = setup
    before = scene.node_id_maps.copy()
    gone = _visible_node(scene)
    edited = graph.without([gone])
    with pytest.raises(StaleSceneError, match="describes graph revision"):
        scene.check_graph(edited)
    derived = scene.for_graph(edited)
    derived.check_graph(edited)
    assert gone not in [n.node_id for n in derived.nodes]
    assert not derived.maps_valid
    with pytest.raises(StaleSceneError, match="re-render"):
        derived.masks([1])
    # the original scene is unchanged and still valid for the original graph
    np.testing.assert_array_equal(scene.node_id_maps, before)
    assert scene.maps_valid and len(scene.nodes) == len(graph.object_nodes)


def test_removal_with_the_log_re_renders_the_maps(setup) -> None:
    log, graph, scene = setup
    gone = _visible_node(scene)
    edited = graph.without([gone])
    derived = scene.for_graph(edited, log)
    assert derived.maps_valid and derived.maps_revision == edited.revision
    assert not derived.masks([gone]).any() and scene.masks([gone]).any()
    np.testing.assert_array_equal(derived.node_id_maps, render_node_id_maps(edited, log).maps)


def test_inserted_nodes_get_an_entry(setup) -> None:
    log, graph, scene = setup
    car = graph.node(_visible_node(scene))
    edited = graph.with_node(dataclasses.replace(car, node_id=0))
    new_id = edited.nodes[-1].node_id
    derived = scene.for_graph(edited, new_nodes={new_id: _bare(new_id, "copy", car.category)})
    assert derived.node(new_id).object_id == "copy" and derived.node(new_id).f_app is None
    bare = scene.for_graph(edited)
    assert bare.node(new_id).object_id == car.object_id and bare.node(new_id).motion is None
    with pytest.raises(ValueError, match="not object nodes"):
        scene.for_graph(edited, new_nodes={99: _bare(99, "x", "vehicle")})
