"""The scene graph of a log's tracks alone: the reconstruction's node numbering and poses, no Gaussians."""

from __future__ import annotations

import numpy as np
import torch

from simsplat_core.scene import InitConfig
from simsplat_core.scene.init import initial_graph
from simsplat_core.scene.track_graph import is_track_graph, track_graph
from simsplat_core.world import WorldConfig, generate_log


def test_track_graph_numbers_and_poses_nodes_like_the_initial_graph() -> None:
    log = generate_log(3, WorldConfig(num_frames=6, width=48, height=32, render_images=False))
    graph = track_graph(log)
    init = initial_graph(log, InitConfig(), set())
    assert is_track_graph(graph) and not is_track_graph(init)
    assert graph.num_gaussians == 0 and np.array_equal(graph.frame_indices, init.frame_indices)
    assert [(n.node_id, n.object_id, n.node_type) for n in graph.object_nodes] == \
        [(n.node_id, n.object_id, n.node_type) for n in init.object_nodes]
    assert {n.node_type for n in graph.object_nodes} >= {"rigid", "nonrigid"}
    for ours, theirs in zip(graph.object_nodes, init.object_nodes):
        assert torch.equal(ours.present, theirs.present)
        assert torch.allclose(ours.poses, theirs.poses)
