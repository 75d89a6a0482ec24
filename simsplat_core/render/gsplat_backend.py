"""gsplat backend: forwards to ``gsplat.rasterization`` (CUDA) and maps its outputs to ours.

gsplat is an optional extra (``pip install gsplat==1.5.3``); nothing here imports it at module load.
Differences to keep in mind (the compositing rules are the same):

* depth is asked of gsplat as accumulated depth (``"D"`` / ``"RGB+D"``) and turned into expected depth
  by :func:`simsplat_core.render.depth.finish_channels`, as for the other backends (gsplat's ``"ED"``
  divides by an alpha floor of 1e-10, which blows up float32 rounding at nearly empty pixels);
* gsplat >= 1.5 bounds each Gaussian by per-axis radii ``ceil(3.33 sqrt(Sigma_xx))`` / ``sigma_yy``
  tightened by the opacity, returned as ``[C, N, 2]``; we report ``max`` of the two as ``[C, N]``
  (0 when culled), so images may differ from the CPU backend at the edges of a Gaussian's tile range.
"""

from __future__ import annotations

import importlib.util

import torch
from torch import Tensor

from simsplat_core.render.binning import tile_grid
from simsplat_core.render.depth import finish_channels
from simsplat_core.render.types import RasterMeta

_GSPLAT_MODES = {"RGB": "RGB", "D": "D", "RGB+ED": "RGB+D"}


def gsplat_available() -> bool:
    """True when the ``gsplat`` package can be imported (it still needs CUDA tensors to run)."""
    return importlib.util.find_spec("gsplat") is not None


def _radii_2d_to_1d(radii: Tensor) -> Tensor:
    """gsplat >= 1.5 radii ``[C, N, 2]`` -> ``[C, N]`` (max extent, 0 when culled); older ``[C, N]`` pass."""
    if radii.dim() == 3:
        visible = (radii > 0).all(dim=-1)
        radii = torch.where(visible, radii.amax(dim=-1), torch.zeros_like(radii[..., 0]))
    return radii.to(torch.int32)


def rasterize_gsplat(
    means: Tensor,  # [N, 3]
    quats: Tensor,  # [N, 4]
    scales: Tensor,  # [N, 3]
    opacities: Tensor,  # [N]
    colors: Tensor,  # [N, D] or [C, N, D]
    viewmats: Tensor,  # [C, 4, 4]
    Ks: Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    near_plane: float,
    far_plane: float,
    render_mode: str,
    backgrounds: Tensor | None,  # [C, D]
    tile_size: int,
    eps2d: float,
    radius_clip: float,
) -> tuple[Tensor, Tensor, RasterMeta]:
    """``gsplat.rasterization`` in non-packed "classic" mode -> ``(colors [C, H, W, X], alphas, meta)``."""
    import gsplat  # noqa: PLC0415  # optional (CUDA) dependency, imported on use

    render, alphas, info = gsplat.rasterization(
        means, quats, scales, opacities, colors, viewmats, Ks, width, height,
        near_plane=near_plane, far_plane=far_plane, radius_clip=radius_clip, eps2d=eps2d, packed=False,
        tile_size=tile_size, backgrounds=backgrounds, render_mode=_GSPLAT_MODES[render_mode],
        rasterize_mode="classic",
    )
    tile_width, tile_height = tile_grid(width, height, tile_size)
    meta = RasterMeta(
        radii=_radii_2d_to_1d(info["radii"]),
        means2d=info["means2d"],
        depths=info["depths"],
        conics=info["conics"],
        opacities=info["opacities"],
        n_cameras=int(viewmats.shape[0]),
        width=width,
        height=height,
        tile_size=tile_size,
        tile_width=int(info.get("tile_width", tile_width)),
        tile_height=int(info.get("tile_height", tile_height)),
        backend="gsplat",
        render_mode=render_mode,
        tiles_per_gauss=info.get("tiles_per_gauss"),
        isect_offsets=info.get("isect_offsets"),
        flatten_ids=info.get("flatten_ids"),
    )
    return finish_channels(render, alphas, render_mode), alphas, meta
