"""Batched rigid-transform helpers in torch (quaternions ``(w, x, y, z)``, 4x4 node->world poses).

All functions broadcast over leading axes; shapes are in the docstrings.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from simsplat_core.render.projection import quat_to_rotmat


def quat_multiply(a: Tensor, b: Tensor) -> Tensor:
    """Hamilton product ``a ⊗ b`` of ``[..., 4]`` quaternions (rotation ``b`` first, then ``a``)."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ], dim=-1)


def rotmat_to_quat(rot: Tensor) -> Tensor:
    """``[..., 3, 3]`` rotation matrices -> ``[..., 4]`` unit quaternions with ``w >= 0``.

    Uses the largest of the four ``4 q_i^2`` candidates for numerical stability (no branches on data).
    """
    m = rot
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    # candidate quaternions, each exact when its leading component is the largest
    cands = torch.stack([
        torch.stack([1 + m00 + m11 + m22, m21 - m12, m02 - m20, m10 - m01], -1),
        torch.stack([m21 - m12, 1 + m00 - m11 - m22, m01 + m10, m02 + m20], -1),
        torch.stack([m02 - m20, m01 + m10, 1 - m00 + m11 - m22, m12 + m21], -1),
        torch.stack([m10 - m01, m02 + m20, m12 + m21, 1 - m00 - m11 + m22], -1),
    ], dim=-2)  # [..., 4, 4]
    diag = torch.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22], -1)
    best = diag.argmax(dim=-1, keepdim=True)  # [..., 1]
    q = torch.take_along_dim(cands, best[..., None].expand(*best.shape[:-1], 1, 4), dim=-2)[..., 0, :]
    q = torch.nn.functional.normalize(q, dim=-1)
    return torch.where(q[..., :1] < 0, -q, q)


def transform_from_rt(rot: Tensor, trans: Tensor) -> Tensor:
    """``[..., 3, 3]`` rotation and ``[..., 3]`` translation -> ``[..., 4, 4]``."""
    out = torch.zeros(rot.shape[:-2] + (4, 4), dtype=rot.dtype, device=rot.device)
    out[..., :3, :3] = rot
    out[..., :3, 3] = trans
    out[..., 3, 3] = 1.0
    return out


def so3_exp(omega: Tensor) -> Tensor:
    """Rodrigues: ``[..., 3]`` axis-angle -> ``[..., 3, 3]`` rotation (smooth at zero)."""
    theta2 = (omega * omega).sum(-1, keepdim=True)[..., None]  # [..., 1, 1]
    theta = torch.sqrt(theta2.clamp(min=1e-12))
    small = theta2 < 1e-8
    a = torch.where(small, 1.0 - theta2 / 6.0, torch.sin(theta) / theta)
    b = torch.where(small, 0.5 - theta2 / 24.0, (1.0 - torch.cos(theta)) / theta2.clamp(min=1e-12))
    x, y, z = omega.unbind(-1)
    zero = torch.zeros_like(x)
    hat = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], -1).reshape(omega.shape[:-1] + (3, 3))
    eye = torch.eye(3, dtype=omega.dtype, device=omega.device).expand_as(hat)
    return eye + a * hat + b * (hat @ hat)


def se3_delta(delta: Tensor) -> Tensor:
    """``[..., 6]`` (translation, axis-angle) -> ``[..., 4, 4]`` (rotation by Rodrigues, translation as is)."""
    return transform_from_rt(so3_exp(delta[..., 3:]), delta[..., :3])


def interpolate_transforms(a: Tensor, b: Tensor, w: Tensor | float) -> Tensor:
    """Blend ``[..., 4, 4]`` rigid transforms: translation lerp, rotation quaternion nlerp (shortest arc).

    ``w`` broadcasts over the leading axes (``[...]``); ``w = 0`` returns ``a`` and ``w = 1`` returns ``b``
    up to rounding of the quaternion round trip (callers skip the blend for integer times).
    """
    w = torch.as_tensor(w, dtype=a.dtype, device=a.device)
    qa, qb = rotmat_to_quat(a[..., :3, :3]), rotmat_to_quat(b[..., :3, :3])
    sign = torch.where((qa * qb).sum(-1, keepdim=True) < 0, -1.0, 1.0).to(a.dtype)
    wq = w[..., None]
    q = torch.nn.functional.normalize((1 - wq) * qa + wq * sign * qb, dim=-1)
    trans = (1 - wq) * a[..., :3, 3] + wq * b[..., :3, 3]
    return transform_from_rt(quat_to_rotmat(q), trans)


def poses_from_boxes(center: np.ndarray, heading: np.ndarray) -> np.ndarray:
    """Box frames ``[T, 4, 4]`` float64 (x along heading, z up, origin at the box centre) from track
    ``center [T, 3]`` and ``heading [T]``."""
    center = np.asarray(center, dtype=np.float64).reshape(-1, 3)
    heading = np.asarray(heading, dtype=np.float64).reshape(-1)
    c, s = np.cos(heading), np.sin(heading)
    out = np.zeros((center.shape[0], 4, 4))
    out[:, 0, 0], out[:, 0, 1] = c, -s
    out[:, 1, 0], out[:, 1, 1] = s, c
    out[:, 2, 2] = 1.0
    out[:, :3, 3] = center
    out[:, 3, 3] = 1.0
    return out


__all__ = [
    "interpolate_transforms",
    "poses_from_boxes",
    "quat_multiply",
    "quat_to_rotmat",
    "rotmat_to_quat",
    "se3_delta",
    "so3_exp",
    "transform_from_rt",
]
