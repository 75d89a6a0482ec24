"""Per-pixel analytic ground and sky.

For every pixel the camera ray is intersected with the ground plane ``z = 0``; hits become world
``xy`` and are shaded procedurally from the ``RoadLayout``: asphalt, dashed lane dividers, the
double yellow centre line, parking-strip edge lines, stop lines, zebra crosswalks, kerbs, sidewalk
tiles and grass, with mild deterministic value noise, soft contact shadows under objects and
distance haze. Ray casting, haze and sky are numpy; the per-pixel material logic is one numba
kernel (branchy code that would need dozens of full-image passes in numpy). Rays that miss the
ground (or hit it farther than ``max_distance``) get a sky gradient and ``inf`` depth.

Because the ray direction is built with unit camera-z component, the ray parameter of the ground hit
*is* the camera z-depth.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from simsplat_core.world.raster import value_noise3
from simsplat_core.world.road import RoadLayout

ASPHALT_R, ASPHALT_G, ASPHALT_B = 0.3, 0.3, 0.32
SIDEWALK_R, SIDEWALK_G, SIDEWALK_B = 0.63, 0.62, 0.6
KERB_R, KERB_G, KERB_B = 0.78, 0.77, 0.75
GRASS_R, GRASS_G, GRASS_B = 0.3, 0.42, 0.2
WHITE_R, WHITE_G, WHITE_B = 0.88, 0.88, 0.86
YELLOW_R, YELLOW_G, YELLOW_B = 0.9, 0.72, 0.12
SKY_HORIZON = np.array([0.82, 0.87, 0.93])
SKY_ZENITH = np.array([0.36, 0.55, 0.85])


@njit(cache=True)
def _noise2(x: float, y: float, seed: int) -> float:
    return value_noise3(x, y, 0.5, seed)


@njit(cache=True)
def _near(x: float, half_width: float) -> bool:
    return abs(x) <= half_width


@njit(cache=True)
def _arm_paint(
    s: float,
    lat: float,
    lanes: int,
    lane_w: float,
    parking_w: float,
    half_w: float,
    cw0: float,
    cw1: float,
    s_stop: float,
) -> int:
    """Marking at along-arm ``s`` / lateral ``lat`` of an arm: 0 none, 1 white, 2 yellow."""
    if cw0 <= s <= cw1:
        if abs(lat) <= half_w - 0.25 and (lat + 0.25) % 1.1 < 0.55:
            return 1
        return 0
    if s < s_stop:
        return 0
    if s <= s_stop + 0.45 and 0.0 <= lat <= lanes * lane_w:
        return 1
    if _near(lat - 0.16, 0.07) or _near(lat + 0.16, 0.07):
        return 2
    if (s - s_stop) % 9.0 < 3.0 or s < s_stop + 8.0:
        for k in range(1, lanes):
            if _near(abs(lat) - k * lane_w, 0.08):
                return 1
    if parking_w > 0.0 and _near(abs(lat) - lanes * lane_w, 0.08):
        return 1
    return 0


@njit(cache=True)
def _ground_kernel(
    u: np.ndarray,
    v: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    geo: np.ndarray,
    shadows: np.ndarray,
    seed: int,
    noise_amp: float,
    out: np.ndarray,
) -> None:
    hw_h, hw_v, lw_h, lw_v = geo[0], geo[1], geo[2], geo[3]
    lanes_h, lanes_v = int(geo[4]), int(geo[5])
    park_h, sw, r = geo[6], geo[7], geo[8]
    gap, cw, stop_gap = geo[9], geo[10], geo[11]
    for p in range(u.shape[0]):
        au, av = abs(u[p]), abs(v[p])
        cross = au <= hw_v or av <= hw_h
        dfc = np.hypot(au - (hw_v + r), av - (hw_h + r))
        in_fillet_box = au <= hw_v + r and av <= hw_h + r and au > hw_v and av > hw_h
        road = cross or (in_fillet_box and dfc >= r)
        fine = _noise2(u[p] * 2.3, v[p] * 2.3, seed)
        if road:
            coarse = _noise2(u[p] * 0.15, v[p] * 0.15, seed + 7)
            f = 1.0 + noise_amp * (1.6 * (fine - 0.5) + 1.2 * (coarse - 0.5))
            cr, cg, cb = ASPHALT_R * f, ASPHALT_G * f, ASPHALT_B * f
            paint = 0
            if au > hw_v and av <= hw_h:  # horizontal arms: E (lat = v) and W (lat = -v)
                lat = v[p] if u[p] > 0 else -v[p]
                cw0 = hw_v + gap
                paint = _arm_paint(au, lat, lanes_h, lw_h, park_h, hw_h, cw0, cw0 + cw, cw0 + cw + stop_gap)
            elif av > hw_h and au <= hw_v:  # vertical arms: N (lat = -u) and S (lat = u)
                lat = -u[p] if v[p] > 0 else u[p]
                cw0 = hw_h + gap
                paint = _arm_paint(av, lat, lanes_v, lw_v, 0.0, hw_v, cw0, cw0 + cw, cw0 + cw + stop_gap)
            if paint > 0:
                wear = 0.9 + 0.1 * fine
                if paint == 1:
                    cr, cg, cb = WHITE_R * wear, WHITE_G * wear, WHITE_B * wear
                else:
                    cr, cg, cb = YELLOW_R * wear, YELLOW_G * wear, YELLOW_B * wear
        elif au <= hw_v + sw or av <= hw_h + sw:
            kerb = (
                (av - hw_h <= 0.25 and au > hw_v + r)
                or (au - hw_v <= 0.25 and av > hw_h + r)
                or (in_fillet_box and r - dfc <= 0.25)
            )
            if kerb:
                cr, cg, cb = KERB_R, KERB_G, KERB_B
            else:
                tile = (u[p] % 1.6) < 0.06 or (v[p] % 1.6) < 0.06
                f = (1.0 + noise_amp * (fine - 0.5)) * (0.85 if tile else 1.0)
                cr, cg, cb = SIDEWALK_R * f, SIDEWALK_G * f, SIDEWALK_B * f
        else:
            g = _noise2(u[p] * 0.7, v[p] * 0.7, seed + 3)
            f = 0.8 + 0.4 * g + noise_amp * (fine - 0.5)
            cr, cg, cb = GRASS_R * f, GRASS_G * f, GRASS_B * f
        # contact shadows: point in convex counter-clockwise quads
        for k in range(shadows.shape[0]):
            inside = True
            for e in range(4):
                ax, ay = shadows[k, e, 0], shadows[k, e, 1]
                bx, by = shadows[k, (e + 1) % 4, 0], shadows[k, (e + 1) % 4, 1]
                if (bx - ax) * (y[p] - ay) - (by - ay) * (x[p] - ax) < 0.0:
                    inside = False
                    break
            if inside:
                cr *= 0.5
                cg *= 0.5
                cb *= 0.5
                break
        out[p, 0] = cr
        out[p, 1] = cg
        out[p, 2] = cb


def _geometry_vector(layout: RoadLayout) -> np.ndarray:
    return np.array(
        [
            layout.hw_h,
            layout.hw_v,
            layout.lane_w_h,
            layout.lane_w_v,
            layout.lanes_h,
            layout.lanes_v,
            layout.parking_w_h,
            layout.sidewalk_w,
            layout.corner_radius,
            layout.crosswalk_gap,
            layout.crosswalk_w,
            layout.stopline_gap,
        ],
        dtype=np.float64,
    )


def ground_color(
    layout: RoadLayout, xy: np.ndarray, seed: int, noise_amp: float, shadows: list[np.ndarray] | None = None
) -> np.ndarray:
    """Procedural ground colour ``[N, 3]`` at world points ``xy [N, 2]``.

    ``shadows`` are ``[4, 2]`` counter-clockwise world quads darkened as contact shadows.
    """
    xy = np.ascontiguousarray(np.atleast_2d(xy), dtype=np.float64)
    uv = layout.to_local(xy)
    quads = (
        np.ascontiguousarray(np.asarray(shadows, dtype=np.float64).reshape(-1, 4, 2))
        if shadows
        else np.zeros((0, 4, 2))
    )
    out = np.empty((xy.shape[0], 3))
    _ground_kernel(
        np.ascontiguousarray(uv[:, 0]),
        np.ascontiguousarray(uv[:, 1]),
        np.ascontiguousarray(xy[:, 0]),
        np.ascontiguousarray(xy[:, 1]),
        _geometry_vector(layout),
        quads,
        int(seed),
        float(noise_amp),
        out,
    )
    return out


def pixel_rays(K: np.ndarray, cam_to_world: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """World-space rays through pixel centres.

    Returns:
        origin: ``[3]`` camera centre.
        dirs: ``[H, W, 3]`` directions with unit camera-z component (so ray parameter = z-depth).
    """
    j, i = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    x = (j - K[0, 2]) / K[0, 0]
    y = (i - K[1, 2]) / K[1, 1]
    d_cam = np.stack([x, y, np.ones_like(x)], axis=-1)
    return cam_to_world[:3, 3].copy(), d_cam @ cam_to_world[:3, :3].T


def sky_color(dirs: np.ndarray) -> np.ndarray:
    """Sky gradient ``[N, 3]`` for world ray directions ``[N, 3]``."""
    elev = dirs[:, 2] / np.linalg.norm(dirs, axis=1)
    t = np.clip(elev / 0.6, 0.0, 1.0) ** 0.6
    return SKY_HORIZON[None] * (1 - t[:, None]) + SKY_ZENITH[None] * t[:, None]


def render_background(
    layout: RoadLayout,
    K: np.ndarray,
    cam_to_world: np.ndarray,
    width: int,
    height: int,
    seed: int,
    noise_amp: float,
    max_distance: float,
    shadows: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ground and sky for one camera.

    Args:
        shadows: optional list of ``[4, 2]`` world footprints (convex, any orientation) darkened as
            contact shadows.

    Returns:
        color ``[H, W, 3]`` float32, depth ``[H, W]`` float32 (``inf`` for sky), ground ``[H, W]`` bool.
    """
    origin, dirs = pixel_rays(K, cam_to_world, width, height)
    flat = dirs.reshape(-1, 3)
    dz = flat[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(dz < -1e-9, -origin[2] / dz, np.inf)
    dist = t * np.linalg.norm(flat, axis=1)
    ground = np.isfinite(t) & (dist <= max_distance)
    color = np.empty((flat.shape[0], 3))
    color[~ground] = sky_color(flat[~ground])
    idx = np.nonzero(ground)[0]
    if idx.size:
        xy = origin[None, :2] + t[idx, None] * flat[idx, :2]
        col = ground_color(layout, xy, seed, noise_amp, shadows)
        haze = 1.0 - np.exp(-dist[idx] / 220.0)
        col = col * (1 - haze[:, None]) + SKY_HORIZON[None] * haze[:, None]
        color[idx] = col
    depth = np.where(ground, t, np.inf).astype(np.float32)
    return (
        np.clip(color, 0.0, 1.0).astype(np.float32).reshape(height, width, 3),
        depth.reshape(height, width),
        ground.reshape(height, width),
    )
