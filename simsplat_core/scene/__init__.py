"""Scene-graph 4D Gaussian scenes (SIMSplat Sec. 3.1): reconstruction, composition, rendering, records.

    from simsplat_core.scene import ReconstructionConfig, reconstruct
    result = reconstruct(log, ReconstructionConfig())
    composed = result.graph.at(12.5)                     # world-space Gaussians at frame 12.5
    images = result.graph.render(12, cam_to_world, Ks, 240, 160)
    records = result.graph.to_records("synth-000000")    # plain numpy, ready for Parquet

Modules: ``gaussians`` (GaussianSet), ``nodes`` (background / rigid / non-rigid), ``graph`` (SceneGraph,
``at``), ``composed`` (ComposedGaussians), ``render`` (SceneRender, node ids), ``records``
(SceneRecords), ``init`` (initialisation from depth or at random), ``knn``, ``transforms``, ``optim``
(Adam groups per node), ``densify`` (DensifyStrategy and row ops), ``config`` (ReconstructionConfig),
``views`` (camera batches of a log), ``evaluate`` (held-out metrics), ``losses`` (L1/D-SSIM training
losses, the SSIM kernel), ``pose_track`` (PoseTrack, extrapolation policies: poses at any time),
``trainer`` (reconstruct).

Graphs are values: ``graph.without(ids)``, ``graph.with_node(node, poses)``, ``graph.with_poses(id, poses)``,
``graph.to(device)`` return new graphs and leave the original unchanged.
"""

from simsplat_core.scene.composed import ComposedGaussians
from simsplat_core.scene.config import (
    ConfigError,
    DensifyConfig,
    InitConfig,
    LearningRates,
    LossWeights,
    ParamLRs,
    ReconstructionConfig,
)
from simsplat_core.scene.densify import DensifyState, DensifyStrategy
from simsplat_core.scene.evaluate import TestFrameRender
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.nodes import NODE_TYPES, BackgroundNode, NonRigidNode, ObjectNode, RigidNode, SceneNode
from simsplat_core.scene.pose_track import Extrapolation, OffsetExtrapolation, PoseTrack
from simsplat_core.scene.records import SceneRecords
from simsplat_core.scene.render import SceneRender
from simsplat_core.scene.trainer import ReconstructionResult, reconstruct

__all__ = [
    "NODE_TYPES",
    "BackgroundNode",
    "ComposedGaussians",
    "ConfigError",
    "DensifyConfig",
    "DensifyState",
    "DensifyStrategy",
    "Extrapolation",
    "GaussianSet",
    "InitConfig",
    "LearningRates",
    "LossWeights",
    "NonRigidNode",
    "ObjectNode",
    "OffsetExtrapolation",
    "ParamLRs",
    "PoseTrack",
    "ReconstructionConfig",
    "ReconstructionResult",
    "RigidNode",
    "SceneGraph",
    "SceneNode",
    "SceneRecords",
    "SceneRender",
    "TestFrameRender",
    "reconstruct",
]
