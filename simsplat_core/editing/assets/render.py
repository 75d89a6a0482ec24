"""An asset rendered alone with the project's rasterizer, and captioned from its own renders.

    rgb, alpha = render_asset(asset)                       # [S, S, 3], [S, S] from the 3/4 front-left view
    caption = describe_asset(asset)                        # the built-in captioner on a few renders

The camera orbits the box centre at ``azimuth_deg`` (0 = in front of the object, on its +x axis;
90 = on its left) and ``elevation_deg`` above the horizon, far enough for the whole box to fit
``fov_deg``. Deformable assets are drawn with the offsets of their first deform frame. Rendering goes
through the same path an inserted asset takes: ``editing.assets.nodes.asset_node`` on a one-frame track, a
``SceneGraph`` with that node only, ``SceneGraph.render``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import torch

from simsplat_core.editing.assets.nodes import asset_node
from simsplat_core.editing.assets.record import Asset
from simsplat_core.language.appearance.captioner import AppearanceCaption, describe_track
from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.pose_track import PoseTrack
from simsplat_core.world.config import CameraSpec
from simsplat_core.world.render import camera_intrinsics, camera_to_ego

#: The contact sheet's view: front-left, from a little above.
SHEET_AZIMUTH_DEG = 35.0
SHEET_ELEVATION_DEG = 20.0
#: Views the captioner looks at (front-left, rear-right, left side), like a passing camera would.
DESCRIBE_AZIMUTHS_DEG = (35.0, 215.0, 90.0)


def orbit_camera(asset: Asset, azimuth_deg: float, elevation_deg: float, size_px: int,
                 fov_deg: float = 40.0) -> tuple[np.ndarray, np.ndarray]:
    """``(cam_to_world [4, 4], K [3, 3])`` of a square camera looking at the box centre (the box frame is
    the world frame)."""
    radius = asset.half_diagonal / math.sin(math.radians(fov_deg) / 2.0) * 1.05
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    eye = radius * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    spec = CameraSpec("asset", yaw_deg=azimuth_deg + 180.0, pitch_deg=elevation_deg, hfov_deg=fov_deg,
                      position=(float(eye[0]), float(eye[1]), float(eye[2])))
    return camera_to_ego(spec), camera_intrinsics(spec, size_px, size_px)


def asset_graph(asset: Asset) -> SceneGraph:
    """A one-frame graph holding only ``asset`` at the origin (its node has id 1; a deformable asset shows
    its first deform frame)."""
    track = PoseTrack(np.zeros(1), torch.eye(4)[None])
    node = asset_node(asset, node_id=1, object_id=asset.asset_id, track=track, arc_length=None,
                      graph_frames=np.zeros(1, dtype=np.int64))
    return SceneGraph(frame_indices=np.zeros(1, dtype=np.int64), nodes=[node])


def render_asset(asset: Asset, *, azimuth_deg: float = SHEET_AZIMUTH_DEG, elevation_deg: float = SHEET_ELEVATION_DEG,
                 size_px: int = 160, background: Sequence[float] = (1.0, 1.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """``(rgb [S, S, 3] float32 in [0, 1], alpha [S, S] float32)`` of the asset alone."""
    c2w, K = orbit_camera(asset, azimuth_deg, elevation_deg, size_px)
    graph = asset_graph(asset)
    with torch.no_grad():
        out = graph.render(0.0, torch.as_tensor(c2w[None], dtype=torch.float32),
                           torch.as_tensor(K[None], dtype=torch.float32), size_px, size_px, with_node_ids=False,
                           background=torch.as_tensor(list(background), dtype=torch.float32))
    return out.rgb[0].numpy().astype(np.float32), out.alpha[0, ..., 0].numpy().astype(np.float32)


def describe_asset(asset: Asset, size_px: int = 128) -> AppearanceCaption:
    """The built-in captioner's description of the asset from ``DESCRIBE_AZIMUTHS_DEG`` renders (subtype
    given: the asset's own)."""
    crops = []
    for k, azimuth in enumerate(DESCRIBE_AZIMUTHS_DEG):
        rgb, alpha = render_asset(asset, azimuth_deg=azimuth, elevation_deg=10.0, size_px=size_px,
                                  background=(0.0, 0.0, 0.0))
        crops.append(ObjectCrop(rgb=rgb, mask=alpha > 0.5, category=asset.category,
                                box_size=np.asarray(asset.size, dtype=np.float64), frame_idx=k, camera="orbit",
                                object_id=asset.asset_id))
    return describe_track(crops, asset.subtype)


__all__ = ["DESCRIBE_AZIMUTHS_DEG", "SHEET_AZIMUTH_DEG", "SHEET_ELEVATION_DEG", "asset_graph", "describe_asset",
           "orbit_camera", "render_asset"]
