"""Evaluation of a reconstructed scene graph on held-out frames.

Metrics follow :mod:`simsplat_core.scene.image_metrics`. Per image: PSNR and SSIM of the full image,
and masked PSNR / SSIM over the *dynamic* pixels: ground-truth instance pixels of objects whose
category is ``vehicle`` or ``pedestrian``. Scene figures are means over images (masked figures over
the images with at least one dynamic pixel, the drivestudio convention). A view with a validity mask
(``ViewBatch.valid``) is scored over its valid pixels only (masked PSNR, ``"same"``-padded masked SSIM).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.image_metrics import masked_psnr, masked_ssim, psnr, ssim
from simsplat_core.scene.views import ViewBatch
from simsplat_core.types import ObjectInfo

DYNAMIC_CATEGORIES: tuple[str, ...] = ("vehicle", "pedestrian")


@dataclass(frozen=True)
class TestFrameRender:
    """One rendered held-out image.

    Attributes:
        frame_idx, camera: which image.
        rgb: ``[H, W, 3]`` float32 render; gt_rgb: ``[H, W, 3]`` float32 ground truth.
        alpha: ``[H, W]`` float32; depth: ``[H, W]`` float32 expected depth.
        node_id: ``[H, W]`` int32 (-1 where alpha < 0.5).
        dynamic_mask: ``[H, W]`` bool ground-truth pixels of vehicles and pedestrians.
        psnr, ssim: full-image metrics; psnr_dynamic, ssim_dynamic: masked (nan without dynamic pixels).
    """

    frame_idx: int
    camera: str
    rgb: np.ndarray
    gt_rgb: np.ndarray
    alpha: np.ndarray
    depth: np.ndarray
    node_id: np.ndarray
    dynamic_mask: np.ndarray
    psnr: float = math.nan
    ssim: float = math.nan
    psnr_dynamic: float = math.nan
    ssim_dynamic: float = math.nan


def dynamic_instance_ids(objects: tuple[ObjectInfo, ...] | list[ObjectInfo]) -> list[int]:
    """Instance ids of the objects counted as dynamic (vehicles and pedestrians)."""
    return [o.instance_id for o in objects if o.category in DYNAMIC_CATEGORIES]


def _mean(values: list[float]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else math.nan


@torch.no_grad()
def render_views(graph: SceneGraph, batches: list[ViewBatch], objects: tuple[ObjectInfo, ...] | list[ObjectInfo],
                 backend: str = "auto", with_node_ids: bool = True) -> list[TestFrameRender]:
    """Render every camera of ``batches`` (which must carry ``rgb``) and score it."""
    dyn_ids = torch.tensor(dynamic_instance_ids(objects) or [-1], dtype=torch.int32)
    out = []
    for batch in batches:
        if batch.rgb is None:
            raise ValueError(f"frame {batch.frame_idx}: no ground-truth images to evaluate against")
        r = graph.render(batch.frame_idx, batch.cam_to_world, batch.Ks, batch.width, batch.height,
                         with_node_ids=with_node_ids, backend=backend)
        rgb = r.rgb.clamp(0.0, 1.0).float().cpu()
        gt = batch.rgb.float().cpu()
        if batch.instance is not None:
            dyn = torch.isin(batch.instance.cpu(), dyn_ids)
        else:
            dyn = torch.zeros(gt.shape[:3], dtype=torch.bool)
        if batch.valid is None:
            p, s = psnr(rgb, gt), ssim(rgb, gt)
        else:  # invalid pixels (e.g. the ego car's body) are not scored
            valid = batch.valid.cpu()
            p, s = masked_psnr(rgb, gt, valid), masked_ssim(rgb, gt, valid)
            dyn = dyn & valid
        pd, sd = masked_psnr(rgb, gt, dyn), masked_ssim(rgb, gt, dyn)
        for c, cam in enumerate(batch.cameras):
            out.append(TestFrameRender(
                frame_idx=batch.frame_idx, camera=cam, rgb=rgb[c].numpy(), gt_rgb=gt[c].numpy(),
                alpha=r.alpha[c, ..., 0].float().cpu().numpy(), depth=r.depth[c, ..., 0].float().cpu().numpy(),
                node_id=(r.node_id[c].cpu().numpy() if r.node_id is not None
                         else np.full(gt.shape[1:3], -1, np.int32)),
                dynamic_mask=dyn[c].numpy(), psnr=float(p[c]), ssim=float(s[c]), psnr_dynamic=float(pd[c]),
                ssim_dynamic=float(sd[c]),
            ))
    return out


def summarise(renders: list[TestFrameRender], split: str) -> dict[str, float]:
    """``{psnr_<split>, ssim_<split>, psnr_<split>_dynamic, ssim_<split>_dynamic, images_<split>}``."""
    return {
        f"psnr_{split}": _mean([r.psnr for r in renders]),
        f"ssim_{split}": _mean([r.ssim for r in renders]),
        f"psnr_{split}_dynamic": _mean([r.psnr_dynamic for r in renders]),
        f"ssim_{split}_dynamic": _mean([r.ssim_dynamic for r in renders]),
        f"images_{split}": float(len(renders)),
    }
