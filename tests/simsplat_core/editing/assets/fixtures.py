"""Small assets and a tiny store for the asset-bank tests (no reconstruction is trained anywhere).

* ``mesh_vehicle``: a world vehicle mesh turned into Gaussians (what a well-seen cut-out looks like:
  body, glass, tyres, lights) in the box frame.
* ``walking_pedestrian``: a few Gaussians whose offsets swing with the distance walked (period
  ``period_m``), so gait retiming can be checked against a formula.
* ``tiny_store``: a synthetic log and its *initial* scene graph (no training) written as a reconstructed
  scene.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import torch

from simsplat_core.color_names import DISPLAY_RGB
from simsplat_core.editing.assets.procedural import mesh_gaussians
from simsplat_core.editing.assets.record import Asset
from simsplat_core.scene import ReconstructionConfig
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.init import initial_graph
from simsplat_core.scene.nodes import OFFSETS
from simsplat_core.world import WorldConfig, generate_log
from simsplat_core.world.mesh import vehicle_mesh
from simsplat_core.world.palette import VEHICLE_KIND_BY_NAME
from storage import ArtifactStore, write_scene, write_scene_log

TINY_WORLD = WorldConfig(num_frames=4, width=96, height=64, test_every=4, render_images=False)
TINY_SCENE_HASH = "0123456789abcdef0123456789abcdef"


def mesh_vehicle(asset_id: str = "t.red-sedan", subtype: str = "sedan", color: str = "red",
                 source_seq: str = "t", **attributes: str) -> Asset:
    """A vehicle of the world's catalogue as Gaussians (5 cm spacing) in the box frame."""
    size = VEHICLE_KIND_BY_NAME[subtype].size
    gaussians = mesh_gaussians(vehicle_mesh(subtype, size, DISPLAY_RGB[color]), 0.05, z_offset=-size[2] / 2)
    return Asset(asset_id=asset_id, category="vehicle", subtype=subtype, caption=f"a {color} {subtype}",
                 color=color, size=size, source_seq=source_seq, source_object=asset_id.split(".")[-1],
                 gaussians=gaussians, attributes=attributes)


def gait_offsets(arc: np.ndarray, n: int = 6) -> torch.Tensor:
    """``[n, T, 3]``: Gaussian ``i`` swings ``0.1 (i + 1) sin(2 pi s)`` along x at walked distance ``s``."""
    amp = 0.1 * (np.arange(n) + 1.0)
    x = amp[:, None] * np.sin(2 * math.pi * np.asarray(arc))[None]  # [n, T]
    out = np.zeros((n, arc.size, 3), np.float32)
    out[..., 0] = x
    return torch.as_tensor(out)


def walking_pedestrian(step_m: float = 0.1, frames: int = 40, asset_id: str = "t.ped", n: int = 6,
                       standing_period: int | None = None) -> Asset:
    """A pedestrian whose source walked ``step_m`` per frame over ``frames`` deform frames with a gait of
    period 1 m (``gait_offsets``); ``standing_period``: a source that did not walk, its offsets periodic in
    time with that many frames."""
    deform = np.arange(frames, dtype=np.int64)
    arc = (step_m * deform).astype(np.float32)
    means = torch.stack([torch.zeros(n), torch.zeros(n), torch.linspace(-0.8, 0.8, n)], dim=1)
    gs = GaussianSet.create(means, torch.full((n,), 0.05), torch.tensor([[0.8, 0.1, 0.1]] * n), 0.9)
    if standing_period is not None:
        arc = np.zeros(frames, np.float32)
        gs.extras[OFFSETS] = gait_offsets(deform / standing_period, n)
    else:
        gs.extras[OFFSETS] = gait_offsets(arc.astype(np.float64), n)
    return Asset(asset_id=asset_id, category="pedestrian", subtype="adult",
                 caption="a pedestrian in a red top and blue trousers", color="red", size=(0.8, 0.6, 1.75),
                 source_seq="t", source_object="ped", gaussians=gs, deform_frames=deform, deform_arc_length=arc,
                 attributes={"lower_color": "blue"})


def tiny_store(root: Path, seed: int = 0) -> tuple[str, str]:
    """``(store root, seq_id)``: a 4-frame synthetic log without pixels and its initial scene graph (random
    initialisation: a few hundred grey Gaussians per object box) as a stored scene."""
    store = ArtifactStore(root)
    log = generate_log(seed, TINY_WORLD)
    write_scene_log(store, log)
    config = ReconstructionConfig()
    graph = initial_graph(log, config.init, set(), seed=config.seed)
    write_scene(store, log.seq_id, TINY_SCENE_HASH, graph.to_records(f"{log.seq_id}/tiny"), {})
    return str(root), log.seq_id
