"""CPU backend: vectorised torch projection -> numba tile binning -> numba compositing.

:func:`rasterize_to_pixels` is the differentiable compositing step (gsplat's function of the same name):
a ``torch.autograd.Function`` whose forward and backward are the numba kernels of
:mod:`simsplat_core.render.cpu_kernels`. Tensors on another device are copied to the host for the
kernels and the results are returned on the inputs' device.
"""

from __future__ import annotations

import numba
import numpy as np
import torch
from torch import Tensor

from simsplat_core.render import cpu_kernels
from simsplat_core.render.binning import isect_tiles, tile_grid
from simsplat_core.render.projection import project_gaussians
from simsplat_core.render.types import Projection, TileIntersections


def _host(t: Tensor) -> np.ndarray:
    """Contiguous host numpy view/copy of a tensor (no grad)."""
    return np.ascontiguousarray(t.detach().cpu().numpy())


def _tile_order(offsets: np.ndarray) -> np.ndarray:
    """Order in which the kernels visit tiles (any order gives the same result). Row-major order keeps
    neighbouring tiles, which share Gaussians, close in time; measured faster than costliest-first.
    Tiles are handed out one at a time (``numba.parallel_chunksize(1)``), which balances the threads."""
    return np.arange(offsets.shape[0] - 1, dtype=np.int64)


class _RasterizeToPixels(torch.autograd.Function):
    """Forward: ``(render [C, H, W, D], alphas [C, H, W, 1])``; backward: gradients w.r.t. ``means2d``,
    ``conics``, ``colors``, ``opacities`` and ``backgrounds``."""

    @staticmethod
    def forward(ctx, means2d, conics, colors, opacities, backgrounds, isect_offsets, flatten_ids, width, height,
                tile_size):
        n_cams, n_gauss, n_dims = colors.shape
        dtype, device = colors.dtype, colors.device
        tile_width = isect_offsets.shape[-1]
        offsets = np.append(_host(isect_offsets).reshape(-1).astype(np.int64), np.int64(flatten_ids.shape[0]))
        ids = _host(flatten_ids).astype(np.int64, copy=False)
        np_dtype = torch.empty((), dtype=dtype).numpy().dtype
        bgs = np.zeros((n_cams, n_dims), dtype=np_dtype) if backgrounds is None else _host(backgrounds)
        order = _tile_order(offsets)
        render = np.empty((n_cams, height, width, n_dims), dtype=np_dtype)
        t_final = np.empty((n_cams, height, width), dtype=np.float64)
        last_ids = np.empty((n_cams, height, width), dtype=np.int64)
        flat = (n_cams * n_gauss,)
        rec = cpu_kernels.pack_records(_host(means2d).reshape(flat + (2,)), _host(conics).reshape(flat + (3,)),
                                       _host(opacities).reshape(flat))
        colors_np = _host(colors).reshape(flat + (n_dims,))
        with numba.parallel_chunksize(1):
            cpu_kernels.rasterize_fwd(rec, colors_np, bgs, offsets, ids, order, width, height, tile_size, tile_width,
                                      render, t_final, last_ids)
        ctx.save_for_backward(means2d, conics, colors, opacities, backgrounds, isect_offsets, flatten_ids)
        ctx.host = (rec, colors_np, offsets, ids, order, bgs, t_final, last_ids)
        ctx.shape = (width, height, tile_size, tile_width)
        # numpy, not torch, for the host-side glue: a torch op this size wakes torch's thread pool, whose
        # spinning threads then compete with numba's for the cores
        alphas = torch.from_numpy((1.0 - t_final).astype(np_dtype, copy=False)[..., None])  # [C, H, W, 1]
        return torch.from_numpy(render).to(device), alphas.to(device)

    @staticmethod
    def backward(ctx, v_render, v_alphas):
        means2d, conics, colors, opacities, backgrounds, _, _ = ctx.saved_tensors
        rec, colors_np, offsets, ids, order, bgs, t_final, last_ids = ctx.host
        width, height, tile_size, tile_width = ctx.shape
        n_cams, n_gauss, n_dims = colors.shape
        dtype, device = colors.dtype, colors.device
        if v_render is None:
            v_render = torch.zeros((n_cams, height, width, n_dims), dtype=dtype, device=device)
        if v_alphas is None:
            v_alphas = torch.zeros((n_cams, height, width, 1), dtype=dtype, device=device)
        v_render_np = _host(v_render)
        v_alpha_np = _host(v_alphas).reshape(n_cams, height, width)
        n_isects = ids.shape[0]
        rows = np.empty((n_isects, cpu_kernels.ROW_COLORS + n_dims), dtype=v_render_np.dtype)
        hit = np.zeros(n_isects, dtype=np.uint8)
        with numba.parallel_chunksize(1):
            cpu_kernels.rasterize_bwd(rec, colors_np, bgs, offsets, ids, order, width, height, tile_size, tile_width,
                                      t_final, last_ids, v_render_np, v_alpha_np, rows, hit)
        tiles_per_cam = (offsets.shape[0] - 1) // n_cams
        cam_starts = np.ascontiguousarray(offsets[::tiles_per_cam])
        grads = torch.from_numpy(cpu_kernels.reduce_rows(rows, hit, ids, cam_starts, n_cams * n_gauss))
        grads = grads.to(dtype=dtype, device=device).reshape(n_cams, n_gauss, -1)  # [C, N, 6 + D]
        k = cpu_kernels
        v_means2d = grads[..., k.ROW_MEAN_X:k.ROW_MEAN_Y + 1]
        v_conics = grads[..., k.ROW_CONIC_A:k.ROW_CONIC_C + 1]
        v_opacities = grads[..., k.ROW_OPACITY]
        v_colors = grads[..., k.ROW_COLORS:]
        v_backgrounds = None
        if backgrounds is not None and ctx.needs_input_grad[4]:
            t_fin = torch.from_numpy(t_final).to(dtype=dtype, device=device)[..., None]  # [C, H, W, 1]
            v_backgrounds = (v_render * t_fin).sum(dim=(1, 2))  # [C, D]
        return v_means2d, v_conics, v_colors, v_opacities, v_backgrounds, None, None, None, None, None


def rasterize_to_pixels(
    means2d: Tensor,  # [C, N, 2]
    conics: Tensor,  # [C, N, 3]
    colors: Tensor,  # [C, N, D]
    opacities: Tensor,  # [C, N]
    width: int,
    height: int,
    tile_size: int,
    isect_offsets: Tensor,  # [C, tile_height, tile_width]
    flatten_ids: Tensor,  # [M]
    backgrounds: Tensor | None = None,  # [C, D]
) -> tuple[Tensor, Tensor]:
    """Differentiable alpha compositing of binned 2D Gaussians (gsplat's ``rasterize_to_pixels``).

    Returns:
        ``render_colors [C, H, W, D]`` (background blended by the final transmittance) and
        ``render_alphas [C, H, W, 1]``.
    """
    n_cams, n_gauss = opacities.shape
    if means2d.shape != (n_cams, n_gauss, 2) or conics.shape != (n_cams, n_gauss, 3):
        raise ValueError(f"means2d {tuple(means2d.shape)} / conics {tuple(conics.shape)} do not match "
                         f"opacities {tuple(opacities.shape)}")
    if colors.dim() != 3 or colors.shape[:2] != (n_cams, n_gauss):
        raise ValueError(f"colors must be [C, N, D] = [{n_cams}, {n_gauss}, D], got {tuple(colors.shape)}")
    dtype = colors.dtype
    return _RasterizeToPixels.apply(  # contiguous host copies are made by numpy inside (see ``_host``)
        means2d.to(dtype), conics.to(dtype), colors, opacities.to(dtype),
        None if backgrounds is None else backgrounds.to(dtype), isect_offsets, flatten_ids, width, height, tile_size,
    )


def project_and_bin(
    means: Tensor, quats: Tensor, scales: Tensor, viewmats: Tensor, Ks: Tensor, width: int, height: int,
    near_plane: float, far_plane: float, eps2d: float, radius_clip: float, tile_size: int,
) -> tuple[Projection, TileIntersections]:
    """Projection (autograd) and tile binning (no grad) of the CPU backend."""
    proj = project_gaussians(means, quats, scales, viewmats, Ks, width, height, near_plane=near_plane,
                             far_plane=far_plane, eps2d=eps2d, radius_clip=radius_clip)
    tile_width, tile_height = tile_grid(width, height, tile_size)
    isects = isect_tiles(proj.means2d, proj.radii, proj.depths, tile_size, tile_width, tile_height)
    return proj, isects
