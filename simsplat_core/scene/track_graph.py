"""A scene graph of a log's tracks alone: the nodes a reconstruction would have, with no Gaussians.

A log without camera images (a Waymo Open Motion scenario, an Argoverse 2 motion-forecasting scenario) is never
reconstructed, yet it is aligned from its tracks and map (``language.alignment.scene_builder``: object nodes
numbered ``1..K`` in object-id order, like ``scene.init.initial_graph``) and it can be edited: the editor reads the
graph for its node ids, object ids, categories and poses, never for pixels. :func:`track_graph` builds that graph:

    graph = track_graph(log)          # background + one node per object, every GaussianSet empty
    graph.metadata["gaussians"]       # "none": nothing to render

Node types follow the log's objects (``rigid`` / ``nonrigid`` / ``static``); a non-rigid node's deformation has
no rows (its deform frames are the frames its track covers). The frame axis is the log's frames ``0..F-1``.
"""

from __future__ import annotations

import numpy as np
import torch

from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.init import object_poses
from simsplat_core.scene.nodes import (
    OFFSETS,
    BackgroundNode,
    NodeFields,
    NonRigidNode,
    PoseFields,
    RigidNode,
    SceneNode,
)
from simsplat_core.types import SceneLog

#: ``SceneGraph.metadata`` key saying the graph holds no Gaussians (value ``"none"``).
GAUSSIANS_KEY = "gaussians"


def is_track_graph(graph: SceneGraph) -> bool:
    """Whether ``graph`` came from :func:`track_graph` (it holds no Gaussians: nothing to render)."""
    return graph.metadata.get(GAUSSIANS_KEY) == "none"


def track_graph(log: SceneLog) -> SceneGraph:
    """The scene graph of ``log``'s tracks with empty Gaussian sets (module docstring).

    Raises:
        ValueError: the log has no frames.
    """
    if log.num_frames <= 0:
        raise ValueError(f"{log.seq_id}: a log without frames has no scene graph")
    frames = np.arange(log.num_frames, dtype=np.int64)
    nodes: list[SceneNode] = [BackgroundNode(node_id=0, gaussians=GaussianSet.empty())]
    for node_id, obj in enumerate(sorted(log.objects, key=lambda o: o.object_id), start=1):
        track = log.track(obj.object_id)
        size = track.size[0] if len(track) else np.ones(3)
        poses, present = object_poses(log, obj, frames)
        common = NodeFields(node_id=node_id, gaussians=GaussianSet.empty(), object_id=obj.object_id,
                            category=obj.category, scale=float(0.5 * np.linalg.norm(size)))
        pose_kw = PoseFields(poses=torch.as_tensor(poses, dtype=torch.float32), present=torch.as_tensor(present))
        if obj.node_type == "nonrigid":
            deform = frames[present] if present.any() else frames[:1]
            common["gaussians"] = GaussianSet.empty(extras_shapes={OFFSETS: (int(deform.size), 3)})
            nodes.append(NonRigidNode(**common, **pose_kw, deform_frames=deform))
        else:
            nodes.append(RigidNode(**common, **pose_kw, static=obj.node_type == "static"))
    metadata = {"seq_id": log.seq_id, "source": log.source, "init": "tracks", GAUSSIANS_KEY: "none"}
    return SceneGraph(frame_indices=frames, nodes=nodes, metadata=metadata)


__all__ = ["GAUSSIANS_KEY", "is_track_graph", "track_graph"]
