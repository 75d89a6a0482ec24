"""Fused EWA projection on the CPU: numba forward and hand-derived backward (gsplat's
``fully_fused_projection`` as one pass per Gaussian instead of ~40 torch ops).

Same contract and rules as :func:`simsplat_core.render.projection.project_gaussians_torch` (see
:mod:`simsplat_core.render.projection` for the maths). Gradients flow to ``means``, ``quats`` and
``scales``; the camera parameters (``viewmats``, ``Ks``) get none, so the caller uses the torch path
when they require grad. Arithmetic is float64 inside; outputs have the inputs' dtype.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from numba import njit, prange
from torch import Tensor

from simsplat_core.render.types import FOV_MARGIN, Projection


@njit(cache=True)
def _rotation(qw, qx, qy, qz):  # pragma: no cover - numba
    """Rotation matrix of a unit quaternion as a ``(3, 3)`` float64 array."""
    rot = np.empty((3, 3))
    rot[0, 0] = 1.0 - 2.0 * (qy * qy + qz * qz)
    rot[0, 1] = 2.0 * (qx * qy - qw * qz)
    rot[0, 2] = 2.0 * (qx * qz + qw * qy)
    rot[1, 0] = 2.0 * (qx * qy + qw * qz)
    rot[1, 1] = 1.0 - 2.0 * (qx * qx + qz * qz)
    rot[1, 2] = 2.0 * (qy * qz - qw * qx)
    rot[2, 0] = 2.0 * (qx * qz - qw * qy)
    rot[2, 1] = 2.0 * (qy * qz + qw * qx)
    rot[2, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)
    return rot


@njit(cache=True, parallel=True, fastmath=False)
def project_fwd(means, quats, scales, viewmats, Ks, limits, width, height, near, far, eps2d, radius_clip,
                means2d, conics, depths, radii):  # pragma: no cover - numba
    """Forward projection; parallel over Gaussians, loop over cameras.

    Args:
        means ``[N, 3]``, quats ``[N, 4]``, scales ``[N, 3]``, viewmats ``[C, 4, 4]``, Ks ``[C, 3, 3]``.
        limits: ``[C, 4]`` float64 clamp limits ``(x_neg, x_pos, y_neg, y_pos)`` of ``x/z``, ``y/z``.
        means2d ``[C, N, 2]``, conics ``[C, N, 3]``, depths ``[C, N]``, radii ``[C, N]`` int32: outputs.
    """
    n_gauss = means.shape[0]
    n_cams = viewmats.shape[0]
    for n in prange(n_gauss):
        qw = float(quats[n, 0])
        qx = float(quats[n, 1])
        qy = float(quats[n, 2])
        qz = float(quats[n, 3])
        q_norm = max(math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz), 1e-12)
        rot = _rotation(qw / q_norm, qx / q_norm, qy / q_norm, qz / q_norm)
        m_world = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                m_world[i, j] = rot[i, j] * float(scales[n, j])
        for c in range(n_cams):
            t = np.empty(3)
            m_cam = np.zeros((3, 3))
            for i in range(3):
                t[i] = float(viewmats[c, i, 3])
                for j in range(3):
                    w_ij = float(viewmats[c, i, j])
                    t[i] += w_ij * float(means[n, j])
                    for k in range(3):
                        m_cam[i, k] += w_ij * m_world[j, k]
            z = t[2]
            depths[c, n] = z
            means2d[c, n, 0] = 0.0
            means2d[c, n, 1] = 0.0
            conics[c, n, 0] = 0.0
            conics[c, n, 1] = 0.0
            conics[c, n, 2] = 0.0
            radii[c, n] = 0
            if not (z >= near and z <= far):
                continue
            fx = float(Ks[c, 0, 0])
            fy = float(Ks[c, 1, 1])
            rz = 1.0 / z
            u = t[0] * rz
            v = t[1] * rz
            uc = min(max(u, -limits[c, 0]), limits[c, 1])
            vc = min(max(v, -limits[c, 2]), limits[c, 3])
            cxx = eps2d
            cxy = 0.0
            cyy = eps2d
            for k in range(3):
                a0 = fx * rz * (m_cam[0, k] - uc * m_cam[2, k])
                a1 = fy * rz * (m_cam[1, k] - vc * m_cam[2, k])
                cxx += a0 * a0
                cxy += a0 * a1
                cyy += a1 * a1
            det = cxx * cyy - cxy * cxy
            if not det > 0.0:
                continue
            mx = fx * u + float(Ks[c, 0, 2])
            my = fy * v + float(Ks[c, 1, 2])
            b = 0.5 * (cxx + cyy)
            radius = math.ceil(3.0 * math.sqrt(b + math.sqrt(max(b * b - det, 0.01))))
            if not (radius > radius_clip and math.isfinite(radius)):
                continue
            if mx + radius <= 0 or mx - radius >= width or my + radius <= 0 or my - radius >= height:
                continue
            radii[c, n] = int(radius)
            means2d[c, n, 0] = mx
            means2d[c, n, 1] = my
            conics[c, n, 0] = cyy / det
            conics[c, n, 1] = -cxy / det
            conics[c, n, 2] = cxx / det


@njit(cache=True, parallel=True, fastmath=False)
def project_bwd(means, quats, scales, viewmats, Ks, limits, eps2d, radii, v_means2d, v_conics, v_depths,  # noqa: C901, PLR0915 -- numba kernel: the backward of project_fwd, one loop nest
                v_means, v_quats, v_scales):  # pragma: no cover - numba
    """Backward of :func:`project_fwd` w.r.t. means, quats and scales (recomputes the forward).

    Culled entries (radius 0) only pass their depth gradient (``depth = z`` is defined for all).
    Outputs ``v_means [N, 3]``, ``v_quats [N, 4]``, ``v_scales [N, 3]`` are overwritten.
    """
    n_gauss = means.shape[0]
    n_cams = viewmats.shape[0]
    for n in prange(n_gauss):
        qw0 = float(quats[n, 0])
        qx0 = float(quats[n, 1])
        qy0 = float(quats[n, 2])
        qz0 = float(quats[n, 3])
        q_norm = max(math.sqrt(qw0 * qw0 + qx0 * qx0 + qy0 * qy0 + qz0 * qz0), 1e-12)
        qw, qx, qy, qz = qw0 / q_norm, qx0 / q_norm, qy0 / q_norm, qz0 / q_norm
        rot = _rotation(qw, qx, qy, qz)
        s = np.empty(3)
        for j in range(3):
            s[j] = float(scales[n, j])
        m_world = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                m_world[i, j] = rot[i, j] * s[j]
        g_mean = np.zeros(3)
        g_m_world = np.zeros((3, 3))
        for c in range(n_cams):
            t = np.empty(3)
            for i in range(3):
                t[i] = float(viewmats[c, i, 3])
                for j in range(3):
                    t[i] += float(viewmats[c, i, j]) * float(means[n, j])
            g_t = np.zeros(3)
            g_t[2] = float(v_depths[c, n])
            if radii[c, n] > 0:
                m_cam = np.zeros((3, 3))
                for i in range(3):
                    for j in range(3):
                        w_ij = float(viewmats[c, i, j])
                        for k in range(3):
                            m_cam[i, k] += w_ij * m_world[j, k]
                fx = float(Ks[c, 0, 0])
                fy = float(Ks[c, 1, 1])
                z = t[2]
                rz = 1.0 / z
                u = t[0] * rz
                v = t[1] * rz
                uc = min(max(u, -limits[c, 0]), limits[c, 1])
                vc = min(max(v, -limits[c, 2]), limits[c, 3])
                a0 = np.empty(3)
                a1 = np.empty(3)
                cxx = eps2d
                cxy = 0.0
                cyy = eps2d
                for k in range(3):
                    a0[k] = fx * rz * (m_cam[0, k] - uc * m_cam[2, k])
                    a1[k] = fy * rz * (m_cam[1, k] - vc * m_cam[2, k])
                    cxx += a0[k] * a0[k]
                    cxy += a0[k] * a1[k]
                    cyy += a1[k] * a1[k]
                det = cxx * cyy - cxy * cxy
                # conic (A, B, C) = (cyy, -cxy, cxx) / det  ->  d/d(cxx, cxy, cyy)
                ga = float(v_conics[c, n, 0])
                gb = float(v_conics[c, n, 1])
                gc = float(v_conics[c, n, 2])
                con_a = cyy / det
                con_b = -cxy / det
                con_c = cxx / det
                g_det = -(ga * con_a + gb * con_b + gc * con_c) / det
                g_cxx = gc / det + g_det * cyy
                g_cyy = ga / det + g_det * cxx
                g_cxy = -gb / det - 2.0 * g_det * cxy
                g_u = fx * float(v_means2d[c, n, 0])
                g_v = fy * float(v_means2d[c, n, 1])
                g_uc = 0.0
                g_vc = 0.0
                g_rz = 0.0
                g_m_cam = np.zeros((3, 3))
                for k in range(3):
                    g_a0 = 2.0 * g_cxx * a0[k] + g_cxy * a1[k]
                    g_a1 = 2.0 * g_cyy * a1[k] + g_cxy * a0[k]
                    g_m_cam[0, k] += fx * rz * g_a0
                    g_m_cam[1, k] += fy * rz * g_a1
                    g_m_cam[2, k] -= fx * rz * uc * g_a0 + fy * rz * vc * g_a1
                    g_rz += fx * (m_cam[0, k] - uc * m_cam[2, k]) * g_a0 + fy * (m_cam[1, k] - vc * m_cam[2, k]) * g_a1
                    g_uc -= fx * rz * m_cam[2, k] * g_a0
                    g_vc -= fy * rz * m_cam[2, k] * g_a1
                if u >= -limits[c, 0] and u <= limits[c, 1]:
                    g_u += g_uc
                if v >= -limits[c, 2] and v <= limits[c, 3]:
                    g_v += g_vc
                g_t[0] += rz * g_u
                g_t[1] += rz * g_v
                g_rz += t[0] * g_u + t[1] * g_v
                g_t[2] -= rz * rz * g_rz
                # m_cam = W m_world  ->  g_m_world += W^T g_m_cam
                for j in range(3):
                    for k in range(3):
                        acc = 0.0
                        for i in range(3):
                            acc += float(viewmats[c, i, j]) * g_m_cam[i, k]
                        g_m_world[j, k] += acc
            # t = W mean + w  ->  g_mean += W^T g_t
            for j in range(3):
                for i in range(3):
                    g_mean[j] += float(viewmats[c, i, j]) * g_t[i]
        for j in range(3):
            v_means[n, j] = g_mean[j]
            acc = 0.0
            for i in range(3):
                acc += g_m_world[i, j] * rot[i, j]
            v_scales[n, j] = acc
        g = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                g[i, j] = g_m_world[i, j] * s[j]
        g_w = 2.0 * (-qz * g[0, 1] + qy * g[0, 2] + qz * g[1, 0] - qx * g[1, 2] - qy * g[2, 0] + qx * g[2, 1])
        g_x = 2.0 * (qy * g[0, 1] + qz * g[0, 2] + qy * g[1, 0] - 2.0 * qx * g[1, 1] - qw * g[1, 2]
                     + qz * g[2, 0] + qw * g[2, 1] - 2.0 * qx * g[2, 2])
        g_y = 2.0 * (-2.0 * qy * g[0, 0] + qx * g[0, 1] + qw * g[0, 2] + qx * g[1, 0] + qz * g[1, 2]
                     - qw * g[2, 0] + qz * g[2, 1] - 2.0 * qy * g[2, 2])
        g_z = 2.0 * (-2.0 * qz * g[0, 0] - qw * g[0, 1] + qx * g[0, 2] + qw * g[1, 0] - 2.0 * qz * g[1, 1]
                     + qy * g[1, 2] + qx * g[2, 0] + qy * g[2, 1])
        # q_unit = q / |q|  ->  g_q = (g_unit - q_unit <q_unit, g_unit>) / |q|
        dot = qw * g_w + qx * g_x + qy * g_y + qz * g_z
        v_quats[n, 0] = (g_w - qw * dot) / q_norm
        v_quats[n, 1] = (g_x - qx * dot) / q_norm
        v_quats[n, 2] = (g_y - qy * dot) / q_norm
        v_quats[n, 3] = (g_z - qz * dot) / q_norm


def _limits(Ks: np.ndarray, width: int, height: int) -> np.ndarray:
    """``[C, 4]`` float64 clamp limits ``(x_neg, x_pos, y_neg, y_pos)`` of ``x/z`` and ``y/z``."""
    k = Ks.astype(np.float64)
    fx, fy, cx, cy = k[:, 0, 0], k[:, 1, 1], k[:, 0, 2], k[:, 1, 2]
    mx, my = FOV_MARGIN * 0.5 * width / fx, FOV_MARGIN * 0.5 * height / fy
    return np.ascontiguousarray(np.stack([cx / fx + mx, (width - cx) / fx + mx, cy / fy + my,
                                          (height - cy) / fy + my], axis=-1))


def _np(t: Tensor) -> np.ndarray:
    return np.ascontiguousarray(t.detach().numpy())


class _FusedProjection(torch.autograd.Function):
    @staticmethod
    def forward(ctx, means, quats, scales, viewmats, Ks, width, height, near, far, eps2d, radius_clip):
        n_cams, n_gauss = viewmats.shape[0], means.shape[0]
        dtype = means.dtype
        args = (_np(means), _np(quats), _np(scales), _np(viewmats), _np(Ks), _limits(_np(Ks), width, height))
        means2d = torch.empty((n_cams, n_gauss, 2), dtype=dtype)
        conics = torch.empty((n_cams, n_gauss, 3), dtype=dtype)
        depths = torch.empty((n_cams, n_gauss), dtype=dtype)
        radii = torch.empty((n_cams, n_gauss), dtype=torch.int32)
        project_fwd(*args, width, height, float(near), float(far), float(eps2d), float(radius_clip),
                    means2d.numpy(), conics.numpy(), depths.numpy(), radii.numpy())
        ctx.args = args
        ctx.eps2d = float(eps2d)
        ctx.radii = radii
        ctx.mark_non_differentiable(radii)
        return means2d, conics, depths, radii

    @staticmethod
    def backward(ctx, v_means2d, v_conics, v_depths, _v_radii):
        means = ctx.args[0]
        dtype = torch.from_numpy(means[:0]).dtype
        n_cams, n_gauss = ctx.radii.shape

        def grad_or_zeros(g: Tensor | None, shape: tuple[int, ...]) -> np.ndarray:
            return np.zeros(shape, dtype=means.dtype) if g is None else _np(g)

        v_means = torch.empty((n_gauss, 3), dtype=dtype)
        v_quats = torch.empty((n_gauss, 4), dtype=dtype)
        v_scales = torch.empty((n_gauss, 3), dtype=dtype)
        project_bwd(*ctx.args, ctx.eps2d, ctx.radii.numpy(), grad_or_zeros(v_means2d, (n_cams, n_gauss, 2)),
                    grad_or_zeros(v_conics, (n_cams, n_gauss, 3)), grad_or_zeros(v_depths, (n_cams, n_gauss)),
                    v_means.numpy(), v_quats.numpy(), v_scales.numpy())
        return v_means, v_quats, v_scales, None, None, None, None, None, None, None, None


def project_gaussians_fused(
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
    """Fused CPU projection (host tensors only; no gradient for ``viewmats`` / ``Ks``)."""
    dtype = means.dtype
    means2d, conics, depths, radii = _FusedProjection.apply(
        means, quats.to(dtype), scales.to(dtype), viewmats.to(dtype), Ks.to(dtype), width, height, near_plane,
        far_plane, eps2d, radius_clip)
    return Projection(means2d=means2d, conics=conics, depths=depths, radii=radii)
