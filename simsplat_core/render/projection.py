"""EWA projection of 3D Gaussians to per-camera 2D Gaussians.

:func:`project_gaussians` picks the fused numba kernel (:mod:`.fused_projection`, hand-written backward)
for host tensors whose camera parameters need no gradient, else the vectorised torch version
(:func:`project_gaussians_torch`, autograd backward, any device). Both implement gsplat's rules:

* ``Sigma = R S S^T R^T`` with ``R`` from the normalised quaternion ``(w, x, y, z)``;
* camera-space mean ``t = W mu + w`` and covariance ``W Sigma W^T``;
* ``Sigma_2D = J W Sigma W^T J^T + eps2d I`` where ``J`` is the Jacobian of the perspective projection
  evaluated at ``t`` with ``t_x / t_z`` and ``t_y / t_z`` clamped to the field of view widened by
  ``FOV_MARGIN * tan(fov / 2)`` on each side;
* conic = ``Sigma_2D^-1``; radius = ``ceil(3 sqrt(lambda_max))`` with
  ``lambda_max = b + sqrt(max(0.01, b^2 - det))``, ``b = trace / 2``;
* culled (radius 0): depth outside ``[near, far]``, ``det <= 0``, ``radius <= radius_clip``, or the
  radius square entirely off-screen.

The covariance is never formed in 3D: with ``M = R S`` and ``A = J W M`` (``[2, 3]`` per camera and
Gaussian), ``Sigma_2D = A A^T``. All divisions use a safe depth so culled entries never produce NaN
gradients.
"""

from __future__ import annotations

import torch
from torch import Tensor

from simsplat_core.render.fused_projection import project_gaussians_fused
from simsplat_core.render.types import FOV_MARGIN, Projection


def quat_to_rotmat(quats: Tensor) -> Tensor:
    """Rotation matrices from ``[N, 4]`` quaternions ``(w, x, y, z)`` (normalised here) -> ``[N, 3, 3]``."""
    q = torch.nn.functional.normalize(quats, p=2.0, dim=-1)
    w, x, y, z = q.unbind(-1)
    rot = torch.stack(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
        ],
        dim=-1,
    )
    return rot.reshape(quats.shape[:-1] + (3, 3))


def fov_limits(Ks: Tensor, width: int, height: int) -> tuple[Tensor, Tensor, Tensor, Tensor]:
    """Clamp limits of ``x/z`` and ``y/z`` used in the Jacobian: ``(x_neg, x_pos, y_neg, y_pos)``, each ``[C, 1]``."""
    fx, fy = Ks[:, 0, 0, None], Ks[:, 1, 1, None]  # [C, 1]
    cx, cy = Ks[:, 0, 2, None], Ks[:, 1, 2, None]  # [C, 1]
    margin_x = FOV_MARGIN * 0.5 * width / fx
    margin_y = FOV_MARGIN * 0.5 * height / fy
    return cx / fx + margin_x, (width - cx) / fx + margin_x, cy / fy + margin_y, (height - cy) / fy + margin_y


@torch.no_grad()
def screen_radii(
    means2d: Tensor,  # [C, N, 2]
    cov_xx: Tensor,  # [C, N]
    cov_xy: Tensor,  # [C, N]
    cov_yy: Tensor,  # [C, N]
    keep: Tensor,  # [C, N] bool (depth and determinant tests passed)
    width: int,
    height: int,
    radius_clip: float,
) -> Tensor:
    """``[C, N]`` int32 radii ``ceil(3 sqrt(lambda_max))``; 0 where culled (``keep`` false, radius at or
    below ``radius_clip``, or the radius square entirely outside the image)."""
    det = cov_xx * cov_yy - cov_xy * cov_xy
    b = 0.5 * (cov_xx + cov_yy)
    lambda_max = b + torch.sqrt(torch.clamp_min(b * b - det, 0.01))
    radius = torch.ceil(3.0 * torch.sqrt(lambda_max))
    mx, my = means2d[..., 0], means2d[..., 1]
    on_screen = (mx + radius > 0) & (mx - radius < width) & (my + radius > 0) & (my - radius < height)
    keep = keep & on_screen & (radius > radius_clip) & torch.isfinite(radius)
    return torch.where(keep, radius, torch.zeros_like(radius)).to(torch.int32)


def project_gaussians_torch(
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
    """Project ``N`` world-space Gaussians into ``C`` pinhole cameras (OpenCV axes), vectorised torch.

    Returns:
        :class:`Projection` with ``means2d [C, N, 2]``, ``conics [C, N, 3]``, ``depths [C, N]`` (all
        differentiable w.r.t. means, quats, scales, viewmats and Ks) and ``radii [C, N]`` int32.
        Culled entries have radius 0 and zero ``means2d`` / ``conics`` (as gsplat leaves them).
    """
    rot = quat_to_rotmat(quats)  # [N, 3, 3]
    m_world = rot * scales[:, None, :]  # [N, 3, 3]   M = R S
    w_rot = viewmats[:, :3, :3]  # [C, 3, 3]
    w_trans = viewmats[:, :3, 3]  # [C, 3]
    means_c = torch.einsum("cij,nj->cni", w_rot, means) + w_trans[:, None, :]  # [C, N, 3]
    m_cam = torch.einsum("cij,njk->cnik", w_rot, m_world)  # [C, N, 3, 3]   W M
    x, y, z = means_c.unbind(-1)  # [C, N]

    valid = (z >= near_plane) & (z <= far_plane)  # [C, N]
    z_safe = torch.where(valid, z, torch.ones_like(z))
    rz = 1.0 / z_safe
    u, v = x * rz, y * rz  # [C, N]
    x_neg, x_pos, y_neg, y_pos = fov_limits(Ks, width, height)
    u_clamped = torch.clamp(u, min=-x_neg, max=x_pos)  # [C, N]
    v_clamped = torch.clamp(v, min=-y_neg, max=y_pos)  # [C, N]
    fx, fy = Ks[:, 0, 0, None], Ks[:, 1, 1, None]  # [C, 1]
    cx, cy = Ks[:, 0, 2, None], Ks[:, 1, 2, None]  # [C, 1]

    # rows of A = J W M:  J = [[fx/z, 0, -fx u_c / z], [0, fy/z, -fy v_c / z]]
    a0 = (fx * rz)[..., None] * (m_cam[..., 0, :] - u_clamped[..., None] * m_cam[..., 2, :])  # [C, N, 3]
    a1 = (fy * rz)[..., None] * (m_cam[..., 1, :] - v_clamped[..., None] * m_cam[..., 2, :])  # [C, N, 3]
    cov_xx = (a0 * a0).sum(-1) + eps2d  # [C, N]
    cov_xy = (a0 * a1).sum(-1)  # [C, N]
    cov_yy = (a1 * a1).sum(-1) + eps2d  # [C, N]
    det = cov_xx * cov_yy - cov_xy * cov_xy
    keep = valid & (det > 0)
    inv_det = 1.0 / torch.where(keep, det, torch.ones_like(det))  # [C, N]
    conics = torch.stack([cov_yy, -cov_xy, cov_xx], dim=-1) * inv_det[..., None]  # [C, N, 3]
    means2d = torch.stack([fx * u + cx, fy * v + cy], dim=-1)  # [C, N, 2]
    radii = screen_radii(means2d.detach(), cov_xx.detach(), cov_xy.detach(), cov_yy.detach(), keep, width,
                         height, radius_clip)  # [C, N]
    visible = (radii > 0)[..., None]  # [C, N, 1]
    means2d = torch.where(visible, means2d, torch.zeros_like(means2d))
    conics = torch.where(visible, conics, torch.zeros_like(conics))
    return Projection(means2d=means2d, conics=conics, depths=z, radii=radii)


def project_gaussians(
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
    """Project Gaussians (gsplat's ``fully_fused_projection``, pinhole, classic): the fused CPU kernel
    when every tensor is on the host and ``viewmats`` / ``Ks`` need no gradient, else the torch version.
    Same outputs either way (see :func:`project_gaussians_torch`)."""
    tensors = (means, quats, scales, viewmats, Ks)
    on_host = all(t.device.type == "cpu" for t in tensors)
    if on_host and not (viewmats.requires_grad or Ks.requires_grad):
        return project_gaussians_fused(means, quats, scales, viewmats, Ks, width, height, near_plane=near_plane,
                                       far_plane=far_plane, eps2d=eps2d, radius_clip=radius_clip)
    return project_gaussians_torch(means, quats, scales, viewmats, Ks, width, height, near_plane=near_plane,
                                   far_plane=far_plane, eps2d=eps2d, radius_clip=radius_clip)
