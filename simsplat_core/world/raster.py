"""Numba triangle rasterizer with a z-buffer: perspective-correct depth and texture, near-plane clipping.

One entry point, ``rasterize_triangles``, draws camera-space triangles into existing colour, depth
and instance buffers (the caller pre-fills them with ground/sky), so the z-test also resolves
objects against the ground. Pixel ``(row i, column j)`` samples the image point ``(j + 0.5, i + 0.5)``
(continuous pixel coordinates, the convention ``project_points`` uses with ``K``).

Shading inside the rasterizer is limited to the per-pixel procedural texture; lighting is baked into
the per-triangle colour by the caller. Textures are deterministic functions of the interpolated
texture coordinate and an integer seed.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from simsplat_core.world.mesh import MAT_FACADE, MAT_PLAIN

_MAT_PLAIN = MAT_PLAIN
_MAT_FACADE = MAT_FACADE


@njit(cache=True, inline="always")
def _hash3(ix: int, iy: int, iz: int, seed: int) -> float:
    h = (ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791) ^ (seed * 2654435761)
    h = h & 0xFFFFFFFF
    h = (h ^ (h >> 16)) * 0x45D9F3B
    h = h & 0xFFFFFFFF
    h = (h ^ (h >> 16)) * 0x45D9F3B
    h = h & 0xFFFFFFFF
    h = h ^ (h >> 16)
    return (h & 0xFFFFFF) / 16777216.0


@njit(cache=True)
def value_noise3(x: float, y: float, z: float, seed: int) -> float:
    """Trilinear value noise in ``[0, 1)`` with smoothstep weights."""
    fx, fy, fz = np.floor(x), np.floor(y), np.floor(z)
    ix, iy, iz = int(fx), int(fy), int(fz)
    tx, ty, tz = x - fx, y - fy, z - fz
    tx = tx * tx * (3.0 - 2.0 * tx)
    ty = ty * ty * (3.0 - 2.0 * ty)
    tz = tz * tz * (3.0 - 2.0 * tz)
    acc = 0.0
    for dz in range(2):
        wz = tz if dz else 1.0 - tz
        for dy in range(2):
            wy = ty if dy else 1.0 - ty
            for dx in range(2):
                wx = tx if dx else 1.0 - tx
                acc += wx * wy * wz * _hash3(ix + dx, iy + dy, iz + dz, seed)
    return acc


@njit(cache=True)
def _clip_near(v: np.ndarray, t: np.ndarray, near: float, out_v: np.ndarray, out_t: np.ndarray) -> int:
    """Clip triangle ``v [3, 3]`` (camera space) with attributes ``t [3, 3]`` to ``z >= near``; returns vertex count."""
    n = 0
    for k in range(3):
        a = k
        b = (k + 1) % 3
        za = v[a, 2]
        zb = v[b, 2]
        a_in = za >= near
        b_in = zb >= near
        if a_in:
            out_v[n, :] = v[a, :]
            out_t[n, :] = t[a, :]
            n += 1
        if a_in != b_in:
            s = (near - za) / (zb - za)
            out_v[n, :] = v[a, :] + s * (v[b, :] - v[a, :])
            out_t[n, :] = t[a, :] + s * (t[b, :] - t[a, :])
            n += 1
    return n


@njit(cache=True)
def _shade(
    color: np.ndarray, mat: int, tx: float, ty: float, tz: float, noise_amp: float, seed: int, out: np.ndarray
) -> None:
    r, g, b = color[0], color[1], color[2]
    if mat == _MAT_FACADE:
        u = tx / 2.8
        w = tz / 3.3
        fu = u - np.floor(u)
        fw = w - np.floor(w)
        if tz > 1.2 and 0.22 < fu < 0.78 and 0.3 < fw < 0.8:
            lit = value_noise3(np.floor(u), np.floor(w), 7.0, seed)
            k = 0.28 + 0.25 * lit
            r = r * k + 0.06
            g = g * k + 0.08
            b = b * k + 0.13
        n = value_noise3(tx * 2.0, ty * 2.0, tz * 2.0, seed)
        f = 1.0 + noise_amp * 2.0 * (n - 0.5)
        r *= f
        g *= f
        b *= f
    elif mat == _MAT_PLAIN:
        n = 0.65 * value_noise3(tx * 3.0, ty * 3.0, tz * 3.0, seed) + 0.35 * value_noise3(
            tx * 11.0, ty * 11.0, tz * 11.0, seed + 1
        )
        f = 1.0 + noise_amp * 2.0 * (n - 0.5)
        r *= f
        g *= f
        b *= f
    out[0] = min(max(r, 0.0), 1.0)
    out[1] = min(max(g, 0.0), 1.0)
    out[2] = min(max(b, 0.0), 1.0)


@njit(cache=True)
def rasterize_triangles(  # noqa: PLR0913 -- numba kernel: arrays and camera scalars, no objects
    tri_cam: np.ndarray,
    tri_tex: np.ndarray,
    tri_color: np.ndarray,
    tri_mat: np.ndarray,
    tri_inst: np.ndarray,
    fx: float,
    fy: float,
    cx: float,
    cy: float,
    near: float,
    noise_amp: float,
    seed: int,
    color_buf: np.ndarray,
    depth_buf: np.ndarray,
    inst_buf: np.ndarray,
) -> None:
    """Draw triangles into the buffers in place (z-test against ``depth_buf``).

    Args:
        tri_cam: ``[M, 3, 3]`` float64 vertices in OpenCV camera coordinates.
        tri_tex: ``[M, 3, 3]`` float32 per-vertex texture coordinates.
        tri_color: ``[M, 3]`` float32 lit base colour.
        tri_mat: ``[M]`` int32 material id (see ``mesh.py``).
        tri_inst: ``[M]`` int32 instance id written to ``inst_buf``.
        fx, fy, cx, cy: pinhole intrinsics.
        near: near clipping plane (metres).
        noise_amp: texture amplitude.
        seed: texture seed.
        color_buf: ``[H, W, 3]`` float32, updated.
        depth_buf: ``[H, W]`` float32 z-depth, updated (``inf`` = empty).
        inst_buf: ``[H, W]`` int32, updated.
    """
    height, width = depth_buf.shape
    cv = np.empty((4, 3))
    ct = np.empty((4, 3))
    px = np.empty(4)
    py = np.empty(4)
    iz = np.empty(4)
    shaded = np.empty(3)
    tex_f = np.empty((3, 3))
    for m in range(tri_cam.shape[0]):
        v = tri_cam[m]
        if v[0, 2] < near and v[1, 2] < near and v[2, 2] < near:
            continue
        for a in range(3):
            for b in range(3):
                tex_f[a, b] = tri_tex[m, a, b]
        nv = _clip_near(v, tex_f, near, cv, ct)
        if nv < 3:
            continue
        for k in range(nv):
            iz[k] = 1.0 / cv[k, 2]
            px[k] = fx * cv[k, 0] * iz[k] + cx
            py[k] = fy * cv[k, 1] * iz[k] + cy
        for f in range(1, nv - 1):
            i0, i1, i2 = 0, f, f + 1
            x0, y0, x1, y1, x2, y2 = px[i0], py[i0], px[i1], py[i1], px[i2], py[i2]
            area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
            if abs(area) < 1e-12:
                continue
            inv_area = 1.0 / area
            xmin = max(int(np.ceil(min(x0, x1, x2) - 0.5)), 0)
            xmax = min(int(np.floor(max(x0, x1, x2) - 0.5)), width - 1)
            ymin = max(int(np.ceil(min(y0, y1, y2) - 0.5)), 0)
            ymax = min(int(np.floor(max(y0, y1, y2) - 0.5)), height - 1)
            if xmin > xmax or ymin > ymax:
                continue
            for i in range(ymin, ymax + 1):
                sy = i + 0.5
                for j in range(xmin, xmax + 1):
                    sx = j + 0.5
                    w0 = ((x1 - sx) * (y2 - sy) - (x2 - sx) * (y1 - sy)) * inv_area
                    w1 = ((x2 - sx) * (y0 - sy) - (x0 - sx) * (y2 - sy)) * inv_area
                    w2 = 1.0 - w0 - w1
                    if w0 < 0.0 or w1 < 0.0 or w2 < 0.0:
                        continue
                    izp = w0 * iz[i0] + w1 * iz[i1] + w2 * iz[i2]
                    if izp <= 0.0:
                        continue
                    z = 1.0 / izp
                    if z >= depth_buf[i, j]:
                        continue
                    a0 = w0 * iz[i0] * z
                    a1 = w1 * iz[i1] * z
                    a2 = w2 * iz[i2] * z
                    tx = a0 * ct[i0, 0] + a1 * ct[i1, 0] + a2 * ct[i2, 0]
                    ty = a0 * ct[i0, 1] + a1 * ct[i1, 1] + a2 * ct[i2, 1]
                    tz = a0 * ct[i0, 2] + a1 * ct[i1, 2] + a2 * ct[i2, 2]
                    _shade(tri_color[m], tri_mat[m], tx, ty, tz, noise_amp, seed, shaded)
                    depth_buf[i, j] = z
                    inst_buf[i, j] = tri_inst[m]
                    color_buf[i, j, 0] = shaded[0]
                    color_buf[i, j, 1] = shaded[1]
                    color_buf[i, j, 2] = shaded[2]
