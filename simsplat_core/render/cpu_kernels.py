"""Numba kernels of the CPU backend: tile binning, compositing forward and compositing backward.

All kernels work on numpy arrays (float32 or float64 inputs; arithmetic is done in float64 inside) and
are parallel over tiles with ``prange``. They implement gsplat's "classic" compositing rules:

* a Gaussian ``g`` is evaluated at the pixels of every tile its ``radius`` square touches;
* ``sigma = 0.5 (a dx^2 + c dy^2) + b dx dy`` with ``(dx, dy) = mean2d - (x + 0.5, y + 0.5)``;
* ``alpha = min(0.999, opacity exp(-sigma))``; skipped when ``sigma < 0`` or ``alpha < 1/255``;
* front to back, ``T <- T (1 - alpha)``; a pixel stops (excluding that Gaussian) once ``T <= 1e-4``.

Inside a tile the loops are Gaussian-major: each Gaussian visits only the pixels of the tile where its
alpha can reach 1/255, i.e. inside the ellipse ``sigma <= log(255 opacity)`` (row by row, the chord of
the ellipse widened by a safety margin). That is an exact shortcut (pixels outside fail the alpha test
anyway), so the result does not depend on it. Gaussian parameters are packed into one float64 cache
line per Gaussian (:func:`pack_records`) so each intersection costs one random read plus its colours.
Along a row of 3 or more pixels ``exp(-sigma)`` is a running product (:func:`_row_exp`: sigma is
quadratic in x), which costs two multiplications per pixel instead of an exponential; it agrees with
``math.exp`` to about 1e-14 relative, and the backward pass forms it identically.

The backward pass walks each tile back to front (gsplat's approach): it recovers the transmittance
``T_i`` by dividing the saved final transmittance by ``(1 - alpha)`` and keeps the colour accumulated
behind the current Gaussian. Each (tile, Gaussian) intersection writes its own gradient row, so tiles
never write to the same memory; :func:`reduce_rows` then sums the rows per Gaussian.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from simsplat_core.render.types import ALPHA_THRESHOLD, MAX_ALPHA, TRANSMITTANCE_MIN

#: Columns of the per-intersection gradient rows: d/d(mean x, mean y, conic a, b, c, opacity), colours.
ROW_MEAN_X, ROW_MEAN_Y, ROW_CONIC_A, ROW_CONIC_B, ROW_CONIC_C, ROW_OPACITY, ROW_COLORS = 0, 1, 2, 3, 4, 5, 6

_BOX_REL_MARGIN = 1e-6
_BOX_ABS_MARGIN = 1e-4
#: Rows of at least this many pixels get ``exp(-sigma)`` as a running product (two exponentials per
#: row and two multiplications per pixel) instead of one exponential per pixel; the forward and the
#: backward pass use the same rule, so they see the same alphas.
RUNNING_EXP_MIN = 3


@njit(cache=True, parallel=True)
def bin_gaussians(means2d, radii, flat_ids, cam_starts, tile_size, tile_width, tile_height):  # pragma: no cover
    """Sorted Gaussian-tile intersections (gsplat's ``isect_tiles`` + ``isect_offset_encode``).

    ``flat_ids`` lists the visible Gaussians of every camera front to back (camera ``c`` owns entries
    ``cam_starts[c]:cam_starts[c + 1]``). A Gaussian touches tiles ``floor(m / s - r / s) ..
    ceil(m / s + r / s)`` (end exclusive, clamped to the grid); a counting sort into tiles keeps the
    depth order inside each tile.

    Args:
        means2d: ``[C * N, 2]``; radii: ``[C * N]``; flat_ids: ``[V]`` int64 ``c * N + n``;
        cam_starts: ``[C + 1]`` int64.

    Returns:
        tiles_per_gauss: ``[C * N]`` int32 (0 for Gaussians not listed).
        offsets: ``[C * tile_height * tile_width + 1]`` int64 start of each tile's run (last = M).
        flatten_ids: ``[M]`` int64 ``c * N + n`` per intersection.
    """
    n_cams = cam_starts.shape[0] - 1
    n_tiles = tile_width * tile_height
    bounds = np.empty((flat_ids.shape[0], 4), np.int32)  # in list order, read sequentially below
    tiles_per_gauss = np.zeros(radii.shape[0], np.int32)
    counts = np.zeros(n_cams * n_tiles + 1, np.int64)
    for c in prange(n_cams):
        for k in range(cam_starts[c], cam_starts[c + 1]):
            g = flat_ids[k]
            r = radii[g] / tile_size
            tmx = means2d[g, 0] / tile_size
            tmy = means2d[g, 1] / tile_size
            x0 = int(min(max(math.floor(tmx - r), 0.0), float(tile_width)))
            y0 = int(min(max(math.floor(tmy - r), 0.0), float(tile_height)))
            x1 = int(min(max(math.ceil(tmx + r), 0.0), float(tile_width)))
            y1 = int(min(max(math.ceil(tmy + r), 0.0), float(tile_height)))
            bounds[k, 0] = x0
            bounds[k, 1] = y0
            bounds[k, 2] = x1
            bounds[k, 3] = y1
            tiles_per_gauss[g] = (x1 - x0) * (y1 - y0)
            for ty in range(y0, y1):
                for tx in range(x0, x1):
                    counts[c * n_tiles + ty * tile_width + tx + 1] += 1
    offsets = np.cumsum(counts)
    cursor = offsets[:-1].copy()
    flatten_ids = np.empty(offsets[-1], np.int64)
    for c in prange(n_cams):
        for k in range(cam_starts[c], cam_starts[c + 1]):
            for ty in range(bounds[k, 1], bounds[k, 3]):
                for tx in range(bounds[k, 0], bounds[k, 2]):
                    t = c * n_tiles + ty * tile_width + tx
                    flatten_ids[cursor[t]] = flat_ids[k]
                    cursor[t] += 1
    return tiles_per_gauss, offsets, flatten_ids


#: Columns of the packed per-Gaussian records (float64) read by the compositing kernels.
REC_MX, REC_MY, REC_CA, REC_CB, REC_CC, REC_OPACITY, REC_LOG_RATIO, REC_EXTENT_Y, REC_WIDTH = 0, 1, 2, 3, 4, 5, 6, 7, 8


@njit(cache=True, parallel=True)
def pack_records(means2d, conics, opacities):  # pragma: no cover - numba
    """One record per Gaussian (8 values, the inputs' dtype): ``(mx, my, a, b, c, opacity, s, ey)``.

    ``s >= log(opacity * 255)`` (alpha can reach 1/255 only where ``sigma <= s``) and ``ey`` is the
    half height of that ellipse; both are rounded up with a relative margin so the pixel sets derived
    from them contain every pixel that passes the exact alpha test, in float32 too. ``ey = -1`` marks a
    Gaussian that can never reach 1/255 (or has non-finite parameters), ``ey = inf`` a conic that is not
    positive definite (whole tile).

    Args:
        means2d: ``[G, 2]``; conics: ``[G, 3]``; opacities: ``[G]``.

    Returns:
        ``[G, 8]`` records.
    """
    n = opacities.shape[0]
    rec = np.empty((n, REC_WIDTH), means2d.dtype)
    for g in prange(n):
        mx = float(means2d[g, 0])
        my = float(means2d[g, 1])
        ca = float(conics[g, 0])
        cb = float(conics[g, 1])
        cc = float(conics[g, 2])
        op = float(opacities[g])
        rec[g, REC_MX] = mx
        rec[g, REC_MY] = my
        rec[g, REC_CA] = ca
        rec[g, REC_CB] = cb
        rec[g, REC_CC] = cc
        rec[g, REC_OPACITY] = op
        finite = (math.isfinite(mx) and math.isfinite(my) and math.isfinite(ca) and math.isfinite(cb)
                  and math.isfinite(cc))
        if not (op >= ALPHA_THRESHOLD and finite):
            rec[g, REC_LOG_RATIO] = 0.0
            rec[g, REC_EXTENT_Y] = -1.0
            continue
        rec[g, REC_LOG_RATIO] = max(math.log(op / ALPHA_THRESHOLD), 0.0) * (1.0 + _BOX_REL_MARGIN) + 1e-12
        s = float(rec[g, REC_LOG_RATIO])
        det = ca * cc - cb * cb
        if det > 0.0 and ca > 0.0 and cc > 0.0:
            rec[g, REC_EXTENT_Y] = math.sqrt(2.0 * s * ca / det) * (1.0 + _BOX_REL_MARGIN) + _BOX_ABS_MARGIN
        else:
            rec[g, REC_EXTENT_Y] = np.inf
    return rec


@njit(cache=True)
def _row_range(rec, g, y0, y1):  # pragma: no cover - numba
    """Inclusive pixel rows ``(ya, yb)`` of tile rows ``[y0, y1)`` where Gaussian ``g`` may reach 1/255."""
    ey = float(rec[g, REC_EXTENT_Y])
    if ey == np.inf:
        return y0, y1 - 1
    my = float(rec[g, REC_MY])
    fya = max(float(y0), math.ceil(my - ey - 0.5))
    fyb = min(float(y1 - 1), math.floor(my + ey - 0.5))
    if fya > fyb:
        return 0, -1
    return int(fya), int(fyb)


@njit(cache=True)
def _col_range(rec, g, dy, x0, x1):  # pragma: no cover - numba
    """Inclusive pixel columns of tile columns ``[x0, x1)`` on the row at offset ``dy = my - py`` where
    ``sigma <= s`` (the chord of the ellipse, widened by a safety margin); the whole tile row for a
    non positive-definite conic."""
    if rec[g, REC_EXTENT_Y] == np.inf:
        return x0, x1 - 1
    ca = float(rec[g, REC_CA])
    cb = float(rec[g, REC_CB])
    det = ca * float(rec[g, REC_CC]) - cb * cb
    disc = max(2.0 * ca * float(rec[g, REC_LOG_RATIO]) - det * dy * dy, 0.0)
    half = math.sqrt(disc) / ca * (1.0 + _BOX_REL_MARGIN) + _BOX_ABS_MARGIN
    centre = float(rec[g, REC_MX]) + cb * dy / ca  # pixel-centre x of the chord's midpoint
    fxa = max(float(x0), math.ceil(centre - half - 0.5))
    fxb = min(float(x1 - 1), math.floor(centre + half - 0.5))
    if fxa > fxb:
        return 0, -1
    return int(fxa), int(fxb)


@njit(cache=True)
def _row_exp(pos_def, count, ca, cb, cc, dx, dy):  # pragma: no cover - numba
    """Start of the running-product exponential on a row of ``count`` pixels whose first pixel has
    offsets ``(dx, dy)``: ``(running, exp(-sigma), exp(-(sigma' - sigma)))``, ``sigma'`` being sigma
    at the next pixel (``dx - 1``). Along a row sigma is quadratic in ``dx``, so its step grows by
    ``ca`` per pixel and ``exp(-sigma)`` of the following pixels is a running product (the step
    ratio is multiplied by ``exp(-ca)`` each pixel). ``running`` is false (callers use ``math.exp``)
    for a conic that is not positive definite or a row shorter than ``RUNNING_EXP_MIN``."""
    if not (pos_def and count >= RUNNING_EXP_MIN):
        return False, 0.0, 0.0
    sigma = 0.5 * (ca * dx * dx + cc * dy * dy) + cb * dx * dy
    return True, math.exp(-sigma), math.exp(-(ca * (0.5 - dx) - cb * dy))


@njit(cache=True, parallel=True, fastmath=False)
def rasterize_fwd(  # noqa: C901, PLR0915 -- numba kernel: one loop nest
    rec, colors, backgrounds, offsets, flatten_ids, tile_order, width, height, tile_size, tile_width,
    render, t_final, last_ids,
):  # pragma: no cover - numba
    """Front-to-back compositing of every tile.

    Args:
        rec: ``[C * N, 8]`` records from :func:`pack_records`; colors: ``[C * N, D]``.
        backgrounds: ``[C, D]`` (zeros when there is no background).
        offsets: ``[C * T + 1]`` int64 run starts (T tiles per camera); flatten_ids: ``[M]`` int64.
        tile_order: ``[C * T]`` int64 permutation of the tiles (load balancing; any order is correct).
        width, height, tile_size, tile_width: image and tile grid.
        render: out ``[C, H, W, D]`` colours (background included).
        t_final: out ``[C, H, W]`` float64 transmittance after the last contributing Gaussian.
        last_ids: out ``[C, H, W]`` int64 index into ``flatten_ids`` of the last contributor (-1: none).
    """
    n_dims = colors.shape[1]
    n_tiles = offsets.shape[0] - 1
    tiles_per_cam = tile_width * ((height + tile_size - 1) // tile_size)
    for j in prange(n_tiles):
        k = tile_order[j]
        cam = k // tiles_per_cam
        t = k - cam * tiles_per_cam
        ty = t // tile_width
        tx = t - ty * tile_width
        x0 = tx * tile_size
        y0 = ty * tile_size
        x1 = min(x0 + tile_size, width)
        y1 = min(y0 + tile_size, height)
        bw = x1 - x0
        npix = bw * (y1 - y0)
        trans = np.ones(npix)
        acc = np.zeros((npix, n_dims))
        last = np.full(npix, -1, np.int64)
        done = np.zeros(npix, np.bool_)
        n_done = 0
        for i in range(offsets[k], offsets[k + 1]):
            g = flatten_ids[i]
            if rec[g, REC_EXTENT_Y] < 0.0:
                continue
            mx = float(rec[g, REC_MX])
            my = float(rec[g, REC_MY])
            ca = float(rec[g, REC_CA])
            cb = float(rec[g, REC_CB])
            cc = float(rec[g, REC_CC])
            op = float(rec[g, REC_OPACITY])
            ya, yb = _row_range(rec, g, y0, y1)
            pos_def = rec[g, REC_EXTENT_Y] != np.inf
            step_ratio = math.exp(-np.float64(ca)) if pos_def else 0.0  # float64 also for float32 records
            for y in range(ya, yb + 1):
                dy = my - (y + 0.5)
                xa, xb = _col_range(rec, g, dy, x0, x1)
                row = (y - y0) * bw - x0
                running, vis_next, ratio = _row_exp(pos_def, xb - xa + 1, ca, cb, cc, mx - (xa + 0.5), dy)
                for x in range(xa, xb + 1):
                    p = row + x
                    vis = vis_next
                    vis_next *= ratio
                    ratio *= step_ratio
                    if done[p]:
                        continue
                    dx = mx - (x + 0.5)
                    sigma = 0.5 * (ca * dx * dx + cc * dy * dy) + cb * dx * dy
                    if sigma < 0.0:
                        continue
                    if not running:
                        vis = math.exp(-sigma)
                    alpha = min(MAX_ALPHA, op * vis)
                    if alpha < ALPHA_THRESHOLD:
                        continue
                    next_t = trans[p] * (1.0 - alpha)
                    if next_t <= TRANSMITTANCE_MIN:
                        done[p] = True
                        n_done += 1
                        continue
                    w = alpha * trans[p]
                    for d in range(n_dims):
                        acc[p, d] += w * colors[g, d]
                    trans[p] = next_t
                    last[p] = i
            if n_done == npix:
                break
        for y in range(y0, y1):
            for x in range(x0, x1):
                p = (y - y0) * bw + x - x0
                for d in range(n_dims):
                    render[cam, y, x, d] = acc[p, d] + trans[p] * backgrounds[cam, d]
                t_final[cam, y, x] = trans[p]
                last_ids[cam, y, x] = last[p]


@njit(cache=True, parallel=True, fastmath=False)
def rasterize_bwd(  # noqa: C901, PLR0915 -- numba kernel: the backward of rasterize_fwd, one loop nest
    rec, colors, backgrounds, offsets, flatten_ids, tile_order, width, height, tile_size, tile_width,
    t_final, last_ids, v_render, v_alpha, rows, hit,
):  # pragma: no cover - numba
    """Back-to-front gradient pass; writes one gradient row per contributing intersection.

    Args:
        rec ... tile_width: as :func:`rasterize_fwd`.
        t_final, last_ids: the forward's saved ``[C, H, W]`` arrays.
        v_render: ``[C, H, W, D]`` gradient of the loss w.r.t. the render.
        v_alpha: ``[C, H, W]`` gradient w.r.t. the alpha image.
        rows: out ``[M, 6 + D]``; row ``i`` gets the gradient w.r.t. Gaussian ``flatten_ids[i]``'s
            (mean x, mean y, conic a, b, c, opacity, colours) from the tile of ``i``.
        hit: out ``[M]`` uint8, zero-initialised; 1 where row ``i`` was written.
    """
    n_dims = colors.shape[1]
    n_tiles = offsets.shape[0] - 1
    tiles_per_cam = tile_width * ((height + tile_size - 1) // tile_size)
    for j in prange(n_tiles):
        k = tile_order[j]
        start = offsets[k]
        if offsets[k + 1] == start:
            continue
        cam = k // tiles_per_cam
        t = k - cam * tiles_per_cam
        ty = t // tile_width
        tx = t - ty * tile_width
        x0 = tx * tile_size
        y0 = ty * tile_size
        x1 = min(x0 + tile_size, width)
        y1 = min(y0 + tile_size, height)
        bw = x1 - x0
        npix = bw * (y1 - y0)
        trans = np.empty(npix)
        tfin = np.empty(npix)
        last = np.empty(npix, np.int64)
        vc = np.empty((npix, n_dims))
        v_a_bg = np.empty(npix)
        buf = np.zeros((npix, n_dims))
        g_col = np.empty(n_dims)
        i_max = -1
        for y in range(y0, y1):
            for x in range(x0, x1):
                p = (y - y0) * bw + x - x0
                tfin[p] = t_final[cam, y, x]
                trans[p] = tfin[p]
                last[p] = last_ids[cam, y, x]
                i_max = max(i_max, last[p])
                bg_dot = 0.0
                for d in range(n_dims):
                    vc[p, d] = v_render[cam, y, x, d]
                    bg_dot += backgrounds[cam, d] * vc[p, d]
                # d(out)/d(alpha_i) through T_final: (v_alpha - <bg, v_render>) * T_final / (1 - alpha_i)
                v_a_bg[p] = v_alpha[cam, y, x] - bg_dot
        for i in range(i_max, start - 1, -1):
            g = flatten_ids[i]
            if rec[g, REC_EXTENT_Y] < 0.0:
                continue
            mx = float(rec[g, REC_MX])
            my = float(rec[g, REC_MY])
            ca = float(rec[g, REC_CA])
            cb = float(rec[g, REC_CB])
            cc = float(rec[g, REC_CC])
            op = float(rec[g, REC_OPACITY])
            ya, yb = _row_range(rec, g, y0, y1)
            g_mx = 0.0
            g_my = 0.0
            g_ca = 0.0
            g_cb = 0.0
            g_cc = 0.0
            g_op = 0.0
            any_hit = False
            pos_def = rec[g, REC_EXTENT_Y] != np.inf
            step_ratio = math.exp(-np.float64(ca)) if pos_def else 0.0  # float64 also for float32 records
            for y in range(ya, yb + 1):
                dy = my - (y + 0.5)
                xa, xb = _col_range(rec, g, dy, x0, x1)
                row = (y - y0) * bw - x0
                running, vis_next, ratio = _row_exp(pos_def, xb - xa + 1, ca, cb, cc, mx - (xa + 0.5), dy)
                for x in range(xa, xb + 1):
                    p = row + x
                    vis = vis_next
                    vis_next *= ratio
                    ratio *= step_ratio
                    if i > last[p]:
                        continue
                    dx = mx - (x + 0.5)
                    sigma = 0.5 * (ca * dx * dx + cc * dy * dy) + cb * dx * dy
                    if sigma < 0.0:
                        continue
                    if not running:
                        vis = math.exp(-sigma)
                    alpha = min(MAX_ALPHA, op * vis)
                    if alpha < ALPHA_THRESHOLD:
                        continue
                    if not any_hit:
                        any_hit = True
                        for d in range(n_dims):
                            g_col[d] = 0.0
                    ra = 1.0 / (1.0 - alpha)
                    t_i = trans[p] * ra
                    trans[p] = t_i
                    fac = alpha * t_i
                    v_al = tfin[p] * ra * v_a_bg[p]
                    for d in range(n_dims):
                        col = float(colors[g, d])
                        g_col[d] += fac * vc[p, d]
                        v_al += (col * t_i - buf[p, d] * ra) * vc[p, d]
                        buf[p, d] += col * fac
                    if op * vis <= MAX_ALPHA:
                        v_sigma = -op * vis * v_al
                        g_ca += 0.5 * v_sigma * dx * dx
                        g_cb += v_sigma * dx * dy
                        g_cc += 0.5 * v_sigma * dy * dy
                        g_mx += v_sigma * (ca * dx + cb * dy)
                        g_my += v_sigma * (cb * dx + cc * dy)
                        g_op += vis * v_al
            if any_hit:
                hit[i] = 1
                rows[i, ROW_MEAN_X] = g_mx
                rows[i, ROW_MEAN_Y] = g_my
                rows[i, ROW_CONIC_A] = g_ca
                rows[i, ROW_CONIC_B] = g_cb
                rows[i, ROW_CONIC_C] = g_cc
                rows[i, ROW_OPACITY] = g_op
                for d in range(n_dims):
                    rows[i, ROW_COLORS + d] = g_col[d]


@njit(cache=True)
def reduce_rows(rows, hit, flatten_ids, cam_starts, n_total):  # pragma: no cover - numba
    """Sum per-intersection gradient rows per Gaussian.

    Args:
        rows: ``[M, K]`` gradient rows, read only where ``hit`` ``[M]`` is non-zero.
        flatten_ids: ``[M]`` int64 target index in ``[0, n_total)``.
        cam_starts: ``[C + 1]`` int64 first row of each camera.
        n_total: ``C * N``.

    Returns:
        ``[n_total, K]`` sums (rows' dtype).
    """
    n_cols = rows.shape[1]
    out = np.zeros((n_total, n_cols), rows.dtype)
    for c in range(cam_starts.shape[0] - 1):
        for i in range(cam_starts[c], cam_starts[c + 1]):
            if hit[i] == 0:
                continue
            g = flatten_ids[i]
            for col in range(n_cols):
                out[g, col] += rows[i, col]
    return out
