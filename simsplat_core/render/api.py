"""The rasterizer's one entry point, :func:`rasterization` (gsplat's functional API, non-packed).

Pipeline per call: project (EWA) -> choose channels for the render mode -> bin into tiles ->
composite -> normalise the expected depth. Backends:

* ``"cpu"``: torch projection + numba binning/compositing (forward and backward), any host CPU;
* ``"reference"``: dense pure-torch per-pixel implementation (tests / benchmarks only; O(C H W N));
* ``"gsplat"``: ``gsplat.rasterization`` on CUDA tensors (optional dependency);
* ``"auto"``: ``"gsplat"`` for CUDA tensors when gsplat is installed, else ``"cpu"``.
"""

from __future__ import annotations

import logging

import torch
from torch import Tensor

from simsplat_core.render.binning import tile_grid
from simsplat_core.render.cpu_backend import project_and_bin, rasterize_to_pixels
from simsplat_core.render.depth import finish_channels
from simsplat_core.render.gsplat_backend import gsplat_available, rasterize_gsplat
from simsplat_core.render.reference import composite_reference, project_reference
from simsplat_core.render.types import BACKENDS, RENDER_MODES, RasterMeta

logger = logging.getLogger(__name__)


def select_backend(backend: str, device: torch.device) -> str:
    """Resolve ``"auto"`` for tensors on ``device``; validate an explicit choice."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; expected one of {BACKENDS}")
    if backend == "auto":
        return "gsplat" if device.type == "cuda" and gsplat_available() else "cpu"
    if backend == "gsplat":
        if device.type != "cuda":
            raise ValueError(f"backend 'gsplat' needs CUDA tensors, got device {device}")
        if not gsplat_available():
            raise ImportError("backend 'gsplat' needs the optional package: pip install gsplat==1.5.3")
    return backend


def _check_inputs(means: Tensor, quats: Tensor, scales: Tensor, opacities: Tensor, colors: Tensor,
                  viewmats: Tensor, Ks: Tensor, backgrounds: Tensor | None, render_mode: str) -> None:
    n_gauss, n_cams = means.shape[0], viewmats.shape[0]
    expected = {"means": (means, (n_gauss, 3)), "quats": (quats, (n_gauss, 4)), "scales": (scales, (n_gauss, 3)),
                "opacities": (opacities, (n_gauss,)), "viewmats": (viewmats, (n_cams, 4, 4)),
                "Ks": (Ks, (n_cams, 3, 3))}
    for name, (tensor, shape) in expected.items():
        if tuple(tensor.shape) != shape:
            raise ValueError(f"{name} must have shape {list(shape)}, got {list(tensor.shape)}")
    if n_cams < 1:
        raise ValueError("need at least one camera (viewmats [C, 4, 4] with C >= 1)")
    if not ((colors.dim() == 2 and colors.shape[0] == n_gauss)
            or (colors.dim() == 3 and colors.shape[:2] == (n_cams, n_gauss))) or colors.shape[-1] < 1:
        raise ValueError(f"colors must be [N, D] or [C, N, D] with N={n_gauss}, C={n_cams}, D>=1, "
                         f"got {list(colors.shape)}")
    if render_mode not in RENDER_MODES:
        raise ValueError(f"unknown render_mode {render_mode!r}; expected one of {RENDER_MODES}")
    if backgrounds is not None and tuple(backgrounds.shape) != (n_cams, colors.shape[-1]):
        raise ValueError(f"backgrounds must be [C, D] = [{n_cams}, {colors.shape[-1]}], got {list(backgrounds.shape)}")


def render_channels(
    colors: Tensor,  # [C, N, D]
    depths: Tensor,  # [C, N]
    backgrounds: Tensor | None,  # [C, D]
    render_mode: str,
) -> tuple[Tensor, Tensor | None]:
    """Channels to composite for ``render_mode`` and their backgrounds (depth channels get background 0)."""
    depth = depths.to(colors.dtype)[..., None]  # [C, N, 1]
    if render_mode == "RGB":
        return colors, backgrounds
    if backgrounds is None:
        return (depth, None) if render_mode == "D" else (torch.cat([colors, depth], dim=-1), None)
    zeros = torch.zeros_like(backgrounds[:, :1])  # [C, 1]
    if render_mode == "D":
        return depth, zeros
    bgs = torch.cat([backgrounds, zeros], dim=-1)  # [C, D + 1]
    return torch.cat([colors, depth], dim=-1), bgs


def rasterization(
    means: Tensor,  # [N, 3]
    quats: Tensor,  # [N, 4]
    scales: Tensor,  # [N, 3]
    opacities: Tensor,  # [N]
    colors: Tensor,  # [N, D] or [C, N, D]
    viewmats: Tensor,  # [C, 4, 4]
    Ks: Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    near_plane: float = 0.01,
    far_plane: float = 1e10,
    render_mode: str = "RGB",
    backgrounds: Tensor | None = None,  # [C, D]
    tile_size: int = 16,
    eps2d: float = 0.3,
    radius_clip: float = 0.0,
    backend: str = "auto",
) -> tuple[Tensor, Tensor, RasterMeta]:
    """Rasterize ``N`` 3D Gaussians into ``C`` pinhole cameras (OpenCV axes), differentiably.

    Args:
        means: ``[N, 3]`` world-space centres.
        quats: ``[N, 4]`` rotations ``(w, x, y, z)``, normalised here.
        scales: ``[N, 3]`` activated scales (``exp(log_scale)``), metres.
        opacities: ``[N]`` activated opacities in ``(0, 1)``.
        colors: ``[N, D]`` or per-camera ``[C, N, D]`` features, any ``D >= 1``.
        viewmats: ``[C, 4, 4]`` world-to-camera transforms.
        Ks: ``[C, 3, 3]`` intrinsics.
        width, height: image size in pixels; pixel ``(x, y)`` has centre ``(x + 0.5, y + 0.5)``.
        near_plane, far_plane: Gaussians with camera depth outside ``[near, far]`` are culled.
        render_mode: ``"RGB"`` (D channels), ``"D"`` (expected depth only) or ``"RGB+ED"`` (D channels
            and the expected depth as the last channel).
        backgrounds: ``[C, D]`` colour blended in with the final transmittance (depth channels use 0).
        tile_size: tile edge in pixels (a Gaussian is evaluated over every tile its radius square touches).
        eps2d: added to the 2D covariance diagonal (low-pass filter).
        radius_clip: Gaussians with a pixel radius at or below this are culled.
        backend: ``"auto"``, ``"cpu"``, ``"gsplat"`` or ``"reference"`` (see the module docstring).

    Returns:
        ``colors [C, H, W, X]`` (``X = D``, 1 or ``D + 1`` by mode), ``alphas [C, H, W, 1]`` and a
        :class:`RasterMeta`; ``meta.means2d`` is part of the graph (``retain_grad()`` it for
        densification statistics).
    """
    _check_inputs(means, quats, scales, opacities, colors, viewmats, Ks, backgrounds, render_mode)
    chosen = select_backend(backend, means.device)
    dtype = means.dtype
    viewmats, Ks = viewmats.to(dtype), Ks.to(dtype)
    if chosen == "gsplat":
        return rasterize_gsplat(means, quats, scales, opacities, colors, viewmats, Ks, width, height,
                                near_plane, far_plane, render_mode, backgrounds, tile_size, eps2d, radius_clip)

    n_cams, n_gauss = viewmats.shape[0], means.shape[0]
    kwargs = dict(near_plane=near_plane, far_plane=far_plane, eps2d=eps2d, radius_clip=radius_clip)
    isects = None
    if chosen == "reference":
        proj = project_reference(means, quats, scales, viewmats, Ks, width, height, **kwargs)
    else:
        proj, isects = project_and_bin(means, quats, scales, viewmats, Ks, width, height, tile_size=tile_size,
                                       **kwargs)
    colors_cn = colors if colors.dim() == 3 else colors[None].expand(n_cams, n_gauss, colors.shape[-1])
    opacities_cn = opacities[None].expand(n_cams, n_gauss)  # [C, N]
    channels, bgs = render_channels(colors_cn, proj.depths, backgrounds, render_mode)
    if isects is None:
        render, alphas = composite_reference(proj.means2d, proj.conics, channels, opacities_cn.to(channels.dtype),
                                             proj.depths, proj.radii, width, height, tile_size, bgs)
    else:
        render, alphas = rasterize_to_pixels(proj.means2d, proj.conics, channels, opacities_cn, width, height,
                                             tile_size, isects.isect_offsets, isects.flatten_ids, bgs)
    render = finish_channels(render, alphas, render_mode)
    tile_width, tile_height = tile_grid(width, height, tile_size)
    meta = RasterMeta(
        radii=proj.radii, means2d=proj.means2d, depths=proj.depths, conics=proj.conics, opacities=opacities_cn,
        n_cameras=n_cams, width=width, height=height, tile_size=tile_size, tile_width=tile_width,
        tile_height=tile_height, backend=chosen, render_mode=render_mode,
        tiles_per_gauss=None if isects is None else isects.tiles_per_gauss,
        isect_offsets=None if isects is None else isects.isect_offsets,
        flatten_ids=None if isects is None else isects.flatten_ids,
    )
    return render, alphas, meta
