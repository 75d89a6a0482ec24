"""Small hand-built scene graphs for the scene tests."""

from __future__ import annotations

import math

import numpy as np
import torch

from simsplat_core.scene import BackgroundNode, GaussianSet, NonRigidNode, RigidNode, SceneGraph
from simsplat_core.scene.nodes import OFFSETS
from simsplat_core.scene.transforms import poses_from_boxes

N_FRAMES = 5


def gaussians(means: list[list[float]], rgb: tuple[float, float, float] = (0.8, 0.2, 0.1), scale: float = 0.2,
              opacity: float = 0.9, features: int = 0, seed: int = 0) -> GaussianSet:
    m = torch.tensor(means, dtype=torch.float32)
    g = torch.Generator().manual_seed(seed)
    quats = torch.randn((m.shape[0], 4), generator=g)
    feats = torch.randn((m.shape[0], features), generator=g) if features else None
    return GaussianSet.create(m, torch.full((m.shape[0],), scale), torch.tensor([rgb] * m.shape[0]), opacity,
                              quats=quats, features=feats)


def rigid_track(n_frames: int = N_FRAMES) -> tuple[np.ndarray, np.ndarray]:
    """``(center [F, 3], heading [F])`` of an object driving along +x while turning left."""
    t = np.arange(n_frames, dtype=np.float64)
    center = np.stack([4.0 + 1.5 * t, 0.5 * t, np.full(n_frames, 0.8)], axis=1)
    heading = 0.3 * t
    return center, heading


def make_graph(features: int = 0) -> SceneGraph:
    """Background (3 Gaussians), a rigid car (node 1, absent in the last frame), a static sign (node 2)
    and a pedestrian (node 3) with offsets at frames 0, 2, 4 (its track misses frame 1)."""
    frames = np.arange(N_FRAMES)
    bg = BackgroundNode(0, gaussians([[20.0, 0.0, 1.0], [25.0, -2.0, 2.0], [30.0, 3.0, 0.0]], (0.3, 0.5, 0.9),
                                     features=features, seed=1), scale=10.0)
    center, heading = rigid_track()
    present = torch.ones(N_FRAMES, dtype=torch.bool)
    present[-1] = False
    car = RigidNode(1, gaussians([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.5, 0.2]], features=features, seed=2),
                    object_id="car", category="vehicle", scale=2.5,
                    poses=torch.as_tensor(poses_from_boxes(center, heading), dtype=torch.float32), present=present)
    sign_pose = poses_from_boxes(np.array([[6.0, -3.0, 1.2]]), np.array([math.pi / 2]))
    sign = RigidNode(2, gaussians([[0.0, 0.0, 0.0], [0.0, 0.0, 0.5]], (0.9, 0.9, 0.1), features=features, seed=3),
                     object_id="sign", category="sign", scale=1.0, static=True,
                     poses=torch.as_tensor(np.repeat(sign_pose, N_FRAMES, axis=0), dtype=torch.float32),
                     present=torch.ones(N_FRAMES, dtype=torch.bool))
    ped_gs = gaussians([[0.0, 0.0, 0.0], [0.0, 0.0, 0.6], [0.1, 0.0, -0.6]], (0.1, 0.8, 0.2), features=features,
                       seed=4)
    deform_frames = np.array([0, 2, 4])
    offsets = torch.zeros((3, 3, 3))
    offsets[:, 1, 0] = 0.2  # frame 2: +0.2 m along x
    offsets[:, 2, 1] = -0.4  # frame 4: -0.4 m along y
    ped_gs.extras[OFFSETS] = offsets
    ped_present = torch.ones(N_FRAMES, dtype=torch.bool)
    ped_present[1] = False
    ped_center = np.stack([np.full(N_FRAMES, 8.0), np.linspace(-2, 2, N_FRAMES), np.full(N_FRAMES, 0.9)], axis=1)
    ped = NonRigidNode(3, ped_gs, object_id="ped", category="pedestrian", scale=1.0,
                       poses=torch.as_tensor(poses_from_boxes(ped_center, np.full(N_FRAMES, 1.0)),
                                             dtype=torch.float32),
                       present=ped_present, deform_frames=deform_frames)
    return SceneGraph(frame_indices=frames, nodes=[bg, car, sign, ped], metadata={"seq_id": "unit"})


def camera(width: int = 64, height: int = 48) -> tuple[torch.Tensor, torch.Tensor]:
    """One OpenCV camera at the origin looking along world +x (z up in the world): ``(cam_to_world
    [1, 4, 4], K [1, 3, 3])``."""
    c2w = torch.zeros(4, 4)
    c2w[:3, :3] = torch.tensor([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    c2w[:3, 3] = torch.tensor([0.0, 0.0, 1.0])
    c2w[3, 3] = 1.0
    f = 0.6 * width
    K = torch.tensor([[f, 0.0, width / 2], [0.0, f, height / 2], [0.0, 0.0, 1.0]])
    return c2w[None], K[None]
