"""Camera rig and the image renderer of the procedural world (independent of any Gaussian rasterizer).

``render_view`` produces RGB, metric z-depth and instance ids for one camera: ground and sky come
analytically per pixel from ``shading.py``; objects, buildings and trees are triangle meshes drawn
by the numba z-buffer rasterizer in ``raster.py`` after Lambert shading with a sun and a sky term.

Intrinsics: square pixels, principal point at the image centre ``(W/2, H/2)``; pixel ``(i, j)``
samples the continuous image point ``(j + 0.5, i + 0.5)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import CV_TO_SENSOR, invert_transform, make_transform
from simsplat_core.world.config import CameraSpec
from simsplat_core.world.mesh import MAT_EMISSIVE, MAT_SMOOTH, Mesh
from simsplat_core.world.raster import rasterize_triangles
from simsplat_core.world.road import RoadLayout
from simsplat_core.world.shading import render_background

NEAR = 0.05


def camera_intrinsics(spec: CameraSpec, width: int, height: int) -> np.ndarray:
    """``[3, 3]`` pinhole matrix for a camera's horizontal field of view."""
    f = (width / 2.0) / np.tan(np.deg2rad(spec.hfov_deg) / 2.0)
    return np.array([[f, 0.0, width / 2.0], [0.0, f, height / 2.0], [0.0, 0.0, 1.0]])


def camera_to_ego(spec: CameraSpec) -> np.ndarray:
    """``[4, 4]`` OpenCV camera -> ego transform of a mounted camera (yaw, then downward pitch)."""
    yaw, pitch = np.deg2rad(spec.yaw_deg), np.deg2rad(spec.pitch_deg)
    cy, sy = np.cos(yaw), np.sin(yaw)
    cp, sp = np.cos(pitch), np.sin(pitch)
    r_yaw = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    # positive pitch tilts the forward (+x) axis towards -z
    r_pitch = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    return make_transform(r_yaw @ r_pitch @ CV_TO_SENSOR, np.asarray(spec.position, dtype=np.float64))


@dataclass(frozen=True)
class Lighting:
    """Sun and sky lighting; ``sun`` is a unit ``[3]`` world direction towards the sun."""

    sun: np.ndarray
    ambient: float = 0.58
    diffuse: float = 0.5

    def shade(self, mesh: Mesh) -> np.ndarray:
        """``[M, 3]`` float32 lit colour per triangle (emissive materials stay unlit)."""
        lam = np.clip(mesh.normals @ self.sun, 0.0, None)
        sky = 0.12 * (0.5 + 0.5 * mesh.normals[:, 2])
        factor = self.ambient + sky + self.diffuse * lam
        lit = mesh.color * factor[:, None].astype(np.float32)
        emissive = mesh.material == MAT_EMISSIVE
        lit[emissive] = mesh.color[emissive]
        return np.clip(lit, 0.0, 1.0).astype(np.float32)


@dataclass(frozen=True)
class DrawList:
    """World-space triangles ready for rendering.

    Attributes:
        tris: ``[M, 3, 3]`` float64 world vertices.
        tex: ``[M, 3, 3]`` float32 texture coordinates.
        color: ``[M, 3]`` float32 lit colours.
        material: ``[M]`` int32 material ids (``MAT_EMISSIVE`` mapped to ``MAT_SMOOTH``).
        instance: ``[M]`` int32 instance ids (0 = background).
    """

    tris: np.ndarray
    tex: np.ndarray
    color: np.ndarray
    material: np.ndarray
    instance: np.ndarray

    @staticmethod
    def build(meshes: list[tuple[Mesh, int]], lighting: Lighting) -> DrawList:
        """Combine ``(world mesh, instance id)`` pairs, baking the lighting into the colours."""
        meshes = [(m, i) for m, i in meshes if len(m)]
        if not meshes:
            z = np.zeros
            return DrawList(
                z((0, 3, 3)), z((0, 3, 3), np.float32), z((0, 3), np.float32), z(0, np.int32), z(0, np.int32)
            )
        merged = Mesh.concat([m for m, _ in meshes])
        inst = np.concatenate([np.full(len(m), i, dtype=np.int32) for m, i in meshes])
        mat = merged.material.copy()
        mat[mat == MAT_EMISSIVE] = MAT_SMOOTH
        return DrawList(merged.tris, merged.tex, lighting.shade(merged), mat, inst)


def _draw_triangles(draw: DrawList, K: np.ndarray, cam_to_world: np.ndarray, noise_amp: float, seed: int,
                    color: np.ndarray, depth: np.ndarray, inst: np.ndarray) -> None:
    """Z-test ``draw``'s triangles into ``color [H, W, 3]``, ``depth [H, W]`` and ``inst [H, W]`` in place."""
    if not len(draw.tris):
        return
    world_to_cam = invert_transform(cam_to_world)
    tri_cam = draw.tris @ world_to_cam[:3, :3].T + world_to_cam[:3, 3]
    rasterize_triangles(
        np.ascontiguousarray(tri_cam),
        np.ascontiguousarray(draw.tex),
        np.ascontiguousarray(draw.color),
        np.ascontiguousarray(draw.material),
        np.ascontiguousarray(draw.instance),
        float(K[0, 0]),
        float(K[1, 1]),
        float(K[0, 2]),
        float(K[1, 2]),
        NEAR,
        float(noise_amp),
        int(seed),
        color,
        depth,
        inst,
    )


def silhouette_view(draw: DrawList, instance_id: int, K: np.ndarray, cam_to_world: np.ndarray, width: int,
                    height: int) -> np.ndarray:
    """``[H, W]`` bool: the pixels instance ``instance_id`` would cover with nothing in front of it (its own
    triangles only, clipped to the image); the unoccluded silhouette that ``render_view``'s instance map cuts
    down where other instances or scenery are nearer."""
    keep = draw.instance == instance_id
    alone = DrawList(draw.tris[keep], draw.tex[keep], draw.color[keep], draw.material[keep], draw.instance[keep])
    color = np.zeros((height, width, 3), dtype=np.float32)
    depth = np.full((height, width), np.inf, dtype=np.float32)
    inst = np.zeros((height, width), dtype=np.int32)
    _draw_triangles(alone, K, cam_to_world, 0.0, 0, color, depth, inst)
    return inst == instance_id


def render_view(
    layout: RoadLayout,
    draw: DrawList,
    K: np.ndarray,
    cam_to_world: np.ndarray,
    width: int,
    height: int,
    seed: int,
    noise_amp: float,
    max_ground_distance: float = 400.0,
    shadows: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Render one camera.

    Returns:
        image ``[H, W, 3]`` float32 in ``[0, 1]``, depth ``[H, W]`` float32 z-depth (``inf`` = sky),
        instance ``[H, W]`` int32, ground ``[H, W]`` bool (pixel shows the ground plane).
    """
    color, depth, ground = render_background(
        layout, K, cam_to_world, width, height, seed, noise_amp, max_ground_distance, shadows
    )
    color = np.ascontiguousarray(color)
    depth = np.ascontiguousarray(depth)
    background_depth = depth.copy()
    inst = np.zeros((height, width), dtype=np.int32)
    _draw_triangles(draw, K, cam_to_world, noise_amp, seed, color, depth, inst)
    ground &= depth == background_depth
    return color, depth, inst, ground
