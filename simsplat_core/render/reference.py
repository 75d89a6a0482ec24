"""Slow, obviously-correct reference rasterizer in plain torch (autograd for gradients).

Used by the tests and the benchmark only. It shares no code with the fast path: the projection is
written with full 3x3 matrices, and compositing evaluates every pixel against every Gaussian
(``O(C H W N)`` memory), sorted by depth, with the same rules:

* a Gaussian is considered at a pixel only if the pixel's tile lies in the Gaussian's tile range
  ``floor((m - r) / s) .. ceil((m + r) / s)`` (gsplat evaluates a Gaussian over whole tiles);
* ``alpha = min(0.999, o exp(-sigma))``, skipped when ``sigma < 0`` or ``alpha < 1/255``;
* the pixel stops before the first Gaussian that would bring the transmittance to ``<= 1e-4``.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from simsplat_core.render.types import (
    ALPHA_THRESHOLD,
    FOV_MARGIN,
    MAX_ALPHA,
    TRANSMITTANCE_MIN,
    Projection,
)


def project_reference(
    means: Tensor,  # [N, 3]
    quats: Tensor,  # [N, 4]
    scales: Tensor,  # [N, 3]
    viewmats: Tensor,  # [C, 4, 4]
    Ks: Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    near_plane: float = 0.01,
    far_plane: float = 1e10,
    eps2d: float = 0.3,
    radius_clip: float = 0.0,
) -> Projection:
    """EWA projection written out with matrices; same contract as ``projection.project_gaussians``."""
    n_cams = viewmats.shape[0]
    q = quats / quats.norm(dim=-1, keepdim=True)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    rot = torch.stack([
        torch.stack([1 - 2 * (y**2 + z**2), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        torch.stack([2 * (x * y + w * z), 1 - 2 * (x**2 + z**2), 2 * (y * z - w * x)], -1),
        torch.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x**2 + y**2)], -1),
    ], dim=-2)  # [N, 3, 3]
    scale_mat = torch.diag_embed(scales)  # [N, 3, 3]
    cov_world = rot @ scale_mat @ scale_mat.transpose(-1, -2) @ rot.transpose(-1, -2)  # [N, 3, 3]

    means2d, conics, depths, radii = [], [], [], []
    for c in range(n_cams):
        w_rot, w_trans = viewmats[c, :3, :3], viewmats[c, :3, 3]
        fx, fy, cx, cy = Ks[c, 0, 0], Ks[c, 1, 1], Ks[c, 0, 2], Ks[c, 1, 2]
        t = means @ w_rot.T + w_trans  # [N, 3]
        cov_cam = w_rot @ cov_world @ w_rot.T  # [N, 3, 3]
        tz = t[:, 2]
        valid = (tz >= near_plane) & (tz <= far_plane)
        tz_safe = torch.where(valid, tz, torch.ones_like(tz))
        lim_x_neg = cx / fx + FOV_MARGIN * 0.5 * width / fx
        lim_x_pos = (width - cx) / fx + FOV_MARGIN * 0.5 * width / fx
        lim_y_neg = cy / fy + FOV_MARGIN * 0.5 * height / fy
        lim_y_pos = (height - cy) / fy + FOV_MARGIN * 0.5 * height / fy
        tx = tz_safe * torch.clamp(t[:, 0] / tz_safe, min=-lim_x_neg, max=lim_x_pos)
        ty = tz_safe * torch.clamp(t[:, 1] / tz_safe, min=-lim_y_neg, max=lim_y_pos)
        zero = torch.zeros_like(tz)
        jac = torch.stack([
            torch.stack([fx / tz_safe, zero, -fx * tx / tz_safe**2], -1),
            torch.stack([zero, fy / tz_safe, -fy * ty / tz_safe**2], -1),
        ], dim=-2)  # [N, 2, 3]
        cov2d = jac @ cov_cam @ jac.transpose(-1, -2)  # [N, 2, 2]
        cov2d = cov2d + eps2d * torch.eye(2, dtype=cov2d.dtype, device=cov2d.device)
        det = cov2d[:, 0, 0] * cov2d[:, 1, 1] - cov2d[:, 0, 1] * cov2d[:, 1, 0]
        keep = valid & (det > 0)
        det_safe = torch.where(keep, det, torch.ones_like(det))
        conic = torch.stack([cov2d[:, 1, 1], -cov2d[:, 0, 1], cov2d[:, 0, 0]], -1) / det_safe[:, None]  # [N, 3]
        mean2d = torch.stack([fx * t[:, 0] / tz_safe + cx, fy * t[:, 1] / tz_safe + cy], -1)  # [N, 2]
        with torch.no_grad():
            # largest eigenvalue in gsplat's closed form (with its 0.01 floor under the square root)
            half_tr = 0.5 * (cov2d[:, 0, 0] + cov2d[:, 1, 1]).detach()
            lam = half_tr + torch.sqrt(torch.clamp(half_tr**2 - det.detach(), min=0.01))
            r = torch.ceil(3.0 * torch.sqrt(lam))
            m = mean2d.detach()
            inside = (m[:, 0] + r > 0) & (m[:, 0] - r < width) & (m[:, 1] + r > 0) & (m[:, 1] - r < height)
            r = torch.where(keep & inside & (r > radius_clip), r, torch.zeros_like(r)).to(torch.int32)
        vis = (r > 0)[:, None]
        means2d.append(torch.where(vis, mean2d, torch.zeros_like(mean2d)))
        conics.append(torch.where(vis, conic, torch.zeros_like(conic)))
        depths.append(tz)
        radii.append(r)
    if n_cams == 0:
        raise ValueError("need at least one camera")
    return Projection(means2d=torch.stack(means2d), conics=torch.stack(conics), depths=torch.stack(depths),
                      radii=torch.stack(radii))


def composite_reference(
    means2d: Tensor,  # [C, N, 2]
    conics: Tensor,  # [C, N, 3]
    colors: Tensor,  # [C, N, D]
    opacities: Tensor,  # [C, N]
    depths: Tensor,  # [C, N]   sort key only
    radii: Tensor,  # [C, N]
    width: int,
    height: int,
    tile_size: int,
    backgrounds: Tensor | None = None,  # [C, D]
) -> tuple[Tensor, Tensor]:
    """Dense per-pixel compositing: ``(render [C, H, W, D], alphas [C, H, W, 1])``."""
    n_cams, n_gauss, n_dims = colors.shape
    dtype, device = colors.dtype, colors.device
    ys, xs = torch.meshgrid(torch.arange(height, device=device), torch.arange(width, device=device), indexing="ij")
    px = (xs.reshape(-1) + 0.5).to(dtype)  # [P]
    py = (ys.reshape(-1) + 0.5).to(dtype)  # [P]
    tile_x = (xs.reshape(-1) // tile_size)[:, None]  # [P, 1]
    tile_y = (ys.reshape(-1) // tile_size)[:, None]  # [P, 1]
    renders, alphas = [], []
    for c in range(n_cams):
        keys = torch.where(radii[c] > 0, depths[c].detach(), torch.full_like(depths[c].detach(), math.inf))
        order = torch.sort(keys, stable=True).indices  # [N] front to back
        m, q, o = means2d[c, order], conics[c, order], opacities[c, order]
        r = radii[c, order].to(dtype)
        with torch.no_grad():  # tile range of each Gaussian (gsplat's isect_tiles)
            x0 = torch.floor(m[:, 0].detach() / tile_size - r / tile_size)
            x1 = torch.ceil(m[:, 0].detach() / tile_size + r / tile_size)
            y0 = torch.floor(m[:, 1].detach() / tile_size - r / tile_size)
            y1 = torch.ceil(m[:, 1].detach() / tile_size + r / tile_size)
            in_tiles = (tile_x >= x0) & (tile_x < x1) & (tile_y >= y0) & (tile_y < y1) & (r > 0)  # [P, N]
        dx = m[None, :, 0] - px[:, None]  # [P, N]
        dy = m[None, :, 1] - py[:, None]  # [P, N]
        sigma = 0.5 * (q[None, :, 0] * dx**2 + q[None, :, 2] * dy**2) + q[None, :, 1] * dx * dy  # [P, N]
        alpha = torch.clamp(o[None, :] * torch.exp(-sigma), max=MAX_ALPHA)  # [P, N]
        used = in_tiles & (sigma >= 0) & (alpha >= ALPHA_THRESHOLD)
        alpha = torch.where(used, alpha, torch.zeros_like(alpha))
        with torch.no_grad():  # the pixel stops before the Gaussian that takes T to <= 1e-4
            t_after = torch.cumprod(1.0 - alpha.detach(), dim=1)  # [P, N]
            keep = t_after > TRANSMITTANCE_MIN
        alpha = torch.where(keep, alpha, torch.zeros_like(alpha))
        ones = torch.ones_like(alpha[:, :1])
        t_before = torch.cumprod(torch.cat([ones, 1.0 - alpha[:, :-1]], dim=1), dim=1)  # [P, N]
        weights = alpha * t_before  # [P, N]
        t_final = torch.prod(1.0 - alpha, dim=1)  # [P]
        render = weights @ colors[c, order]  # [P, D]
        if backgrounds is not None:
            render = render + t_final[:, None] * backgrounds[c][None, :]
        renders.append(render.reshape(height, width, n_dims))
        alphas.append((1.0 - t_final).reshape(height, width, 1))
    return torch.stack(renders), torch.stack(alphas)
