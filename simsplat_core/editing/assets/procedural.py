"""Static assets built procedurally as Gaussians: cones, barriers, barrels, signs, road-works equipment.

Geometry is the synthetic world's: the kinds the world places (traffic cone, striped barrier, stop /
speed limit / parking sign) use ``world.mesh.static_mesh`` itself; the others are assembled here from
the same convex parts (``world.mesh.box`` / ``extrude`` / ``frustum`` -> ``parts_to_mesh``), so the
world's renderer can draw every asset too (``static_kind_mesh``). A mesh becomes Gaussians by
:func:`mesh_gaussians`: flat discs on its triangles, spaced evenly (a Kronecker sequence per triangle,
deterministic), facing the triangle normal, coloured with the world's lit colour of the face
(``world.render.Lighting.shade`` under :data:`ASSET_LIGHTING`), in the box frame (z = 0 at half height).

    cone = procedural_asset("traffic cone", "orange")
    drum = procedural_asset("barrel", "yellow", size=(0.6, 0.6, 1.0))

``STATIC_KINDS`` is the catalogue (nominal size, the colours the bank is built with, aliases people use).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.color_names import COLOR_NAMES, DISPLAY_RGB
from simsplat_core.editing.assets.record import PROCEDURAL, Asset, f32
from simsplat_core.language.appearance.captioner import caption_text
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.init import quats_from_normals
from simsplat_core.world.mesh import (
    MAT_EMISSIVE,
    MAT_PLAIN,
    MAT_SMOOTH,
    PLASTIC,
    TIRE,
    Mesh,
    Part,
    box,
    extrude,
    frustum,
    parts_to_mesh,
    rot_y,
    static_mesh,
)
from simsplat_core.world.render import Lighting

logger = logging.getLogger(__name__)

#: Lighting baked into procedural assets: sun high in the front-left (the world draws its sun at 35-60 deg).
ASSET_LIGHTING = Lighting(sun=np.array([0.45, 0.3, 0.84]) / np.linalg.norm([0.45, 0.3, 0.84]))
#: Disc spacing: this share of the largest box side, at least ``MIN_SPACING_M``.
SPACING_SHARE = 0.012
MIN_SPACING_M = 0.02
#: Disc radius (std) as a share of the sample spacing, its thickness as a share of the radius, opacity.
DISC_RADIUS = 0.7
DISC_THICKNESS = 0.15
DISC_OPACITY = 0.95
#: A procedural asset may be rebuilt at this factor of its nominal size per axis, at most.
RESIZE_RANGE = (0.25, 4.0)
WHITE = DISPLAY_RGB["white"]
LAMP = (0.98, 0.85, 0.2)
GREY_METAL = (0.55, 0.56, 0.58)

Rgb = tuple[float, float, float]


# ---------------------------------------------------------------------------------------------- meshes
def _barrel(size: tuple[float, float, float], col: Rgb) -> list[Part]:
    """A traffic drum: a black ballast ring, then colour bands with two white reflective bands."""
    length, width, height = size
    r = 0.5 * min(length, width)
    parts = [frustum(12, r, 0.95 * r, 0.0, 0.08 * height, PLASTIC)]
    bands = ((0.08, 0.3, col), (0.3, 0.42, WHITE), (0.42, 0.6, col), (0.6, 0.72, WHITE), (0.72, 1.0, col))
    for z0, z1, c in bands:
        parts.append(frustum(12, r * (0.86 - 0.08 * z0), r * (0.86 - 0.08 * z1), z0 * height, z1 * height, c))
    return parts


def _jersey_barrier(size: tuple[float, float, float], col: Rgb) -> list[Part]:
    """A jersey (New Jersey) barrier: two convex prisms, the shallow lower slope and the steep upper one."""
    length, width, height = size
    w, top = width / 2.0, min(0.075, width / 6.0)
    knee_w, knee_h = 0.2 * width + top / 2.0, 0.33 * height
    lower = np.array([[-w, 0.0], [w, 0.0], [w, 0.09 * height], [knee_w, knee_h], [-knee_w, knee_h],
                      [-w, 0.09 * height]])
    upper = np.array([[-knee_w, knee_h], [knee_w, knee_h], [top, height], [-top, height]])
    return [extrude(lower, 0, -length / 2, length / 2, col), extrude(upper, 0, -length / 2, length / 2, col)]


def _road_work_sign(size: tuple[float, float, float], col: Rgb) -> list[Part]:
    """A diamond warning panel (road works) on a grey post, a dark emblem on its face (+x)."""
    length, width, height = size
    r = width / 2.0
    post = box(-length / 2, -length / 2 + 0.06, -0.03, 0.03, 0.0, height - r, GREY_METAL)
    diamond = np.array([[0.0, height - 2 * r], [r, height - r], [0.0, height], [-r, height - r]])
    panel = extrude(diamond, 0, -length / 2 + 0.06, length / 2, col, cap_color=col)
    emblem = box(length / 2 - 0.004, length / 2 + 0.006, -0.3 * r, 0.3 * r, height - 1.35 * r, height - 0.65 * r,
                 (0.05, 0.05, 0.05), MAT_SMOOTH)
    return [post, panel, emblem]


def _wheel(x: float, y0: float, y1: float, radius: float) -> Part:
    ang = np.pi / 8 + 2 * np.pi * np.arange(8) / 8
    poly = np.stack([np.cos(ang), np.sin(ang)], axis=1) * radius + np.array([x, radius])
    return extrude(poly, 1, min(y0, y1), max(y0, y1), TIRE, MAT_SMOOTH)


def _arrow_board(size: tuple[float, float, float], col: Rgb) -> list[Part]:
    """A road-works arrow-board trailer: chassis and drawbar in the body colour, two wheels, a mast and a
    black board facing backwards (-x) with yellow lamps in the shape of a left arrow."""
    length, width, height = size
    lx, wy = length / 2, width / 2
    wheel_r = 0.09 * height
    parts = [
        box(-lx, 0.45 * lx, -0.8 * wy, 0.8 * wy, wheel_r, wheel_r + 0.14 * height, col),
        box(0.45 * lx, lx, -0.05, 0.05, wheel_r + 0.02, wheel_r + 0.08, col),
        box(-0.35 * lx, -0.25 * lx, -0.05, 0.05, wheel_r + 0.14 * height, 0.46 * height, GREY_METAL),
        box(-0.25 * lx, -0.2 * lx, -wy, wy, 0.44 * height, height, PLASTIC),
        _wheel(-0.1 * lx, -wy, -0.8 * wy, wheel_r),
        _wheel(-0.1 * lx, 0.8 * wy, wy, wheel_r),
    ]
    face = -0.25 * lx - 0.01
    z_mid, step = 0.72 * height, 0.085 * height
    lamp = 0.03 * height
    shaft = [(y, z_mid) for y in np.linspace(-0.6 * wy, 0.5 * wy, 6)]  # seen from behind, +y is the viewer's right
    head = [(0.5 * wy - k * 0.12 * wy, z_mid + s * k * step) for k in (1, 2) for s in (-1, 1)]
    for y, z in shaft + head:
        parts.append(box(face, face + 0.02, y - lamp, y + lamp, z - lamp, z + lamp, LAMP, MAT_EMISSIVE))
    return parts


def _excavator(size: tuple[float, float, float], col: Rgb) -> list[Part]:
    """A small excavator as a box set: two crawler tracks, the upper body and cab (glass on three sides),
    a boom and stick reaching forward (+x) and a bucket on the ground."""
    length, width, height = size
    lx, wy = length / 2, width / 2
    track_h, body_top = 0.2 * height, 0.48 * height
    glass = (0.2, 0.25, 0.31)
    parts = [
        box(-0.6 * lx, 0.35 * lx, -wy, -0.55 * wy, 0.0, track_h, TIRE),
        box(-0.6 * lx, 0.35 * lx, 0.55 * wy, wy, 0.0, track_h, TIRE),
        box(-0.55 * lx, 0.3 * lx, -0.55 * wy, 0.55 * wy, 0.04 * height, track_h, PLASTIC),
        box(-0.65 * lx, 0.25 * lx, -0.9 * wy, 0.9 * wy, track_h, body_top, col),
        box(-0.05 * lx, 0.25 * lx, 0.05 * wy, 0.85 * wy, body_top, 0.95 * height, glass, MAT_SMOOTH,
            face_colors={2: col, 5: col}, face_mats={2: MAT_PLAIN, 5: MAT_PLAIN}),
        box(0.2 * lx, 0.75 * lx, -0.12 * wy, 0.12 * wy, 0.42 * height, 0.55 * height, col)
        .moved(rot_y(0.6), np.array([0.2 * lx, 0.0, 0.42 * height])),  # the boom, raised 34 deg
        box(0.6 * lx, 0.7 * lx, -0.1 * wy, 0.1 * wy, 0.22 * height, height, col),
        box(0.62 * lx, lx, -0.35 * wy, 0.35 * wy, 0.0, 0.2 * height, GREY_METAL),
    ]
    return parts


_OWN_MESHES: dict[str, Callable[[tuple[float, float, float], Rgb], list[Part]]] = {
    "barrel": _barrel,
    "jersey barrier": _jersey_barrier,
    "road work sign": _road_work_sign,
    "arrow board": _arrow_board,
    "excavator": _excavator,
}
_WORLD_MESHES = ("traffic cone", "barrier", "stop sign", "speed limit sign", "parking sign")


def static_kind_mesh(subtype: str, size: tuple[float, float, float], rgb: Rgb) -> Mesh:
    """The mesh (object frame: z = 0 on the ground) of a procedural static ``subtype``; the world's own
    mesh for the kinds the world places.

    Raises:
        ValueError: an unknown subtype (the message lists the known ones).
    """
    if subtype in _WORLD_MESHES:
        return static_mesh(subtype, size, rgb)
    if subtype not in _OWN_MESHES:
        raise ValueError(f"unknown procedural static object {subtype!r}; known: {sorted(STATIC_KINDS)}")
    return parts_to_mesh(_OWN_MESHES[subtype](size, rgb))


# ---------------------------------------------------------------------------------------------- catalogue
@dataclass(frozen=True)
class StaticKind:
    """One procedural kind.

    Attributes:
        subtype: the name (``Asset.subtype``).
        size: nominal box ``(length, width, height)`` metres.
        colors: colours the bank is built with (any ``COLOR_NAMES`` colour can be built on request).
        aliases: other words for it (singular), e.g. ``"drum"`` for ``"barrel"``.
    """

    subtype: str
    size: tuple[float, float, float]
    colors: tuple[str, ...]
    aliases: tuple[str, ...] = ()


STATIC_KINDS: dict[str, StaticKind] = {k.subtype: k for k in (
    StaticKind("traffic cone", (0.42, 0.42, 0.72), ("orange", "yellow", "red"), ("cone", "pylon", "road cone")),
    StaticKind("barrier", (2.0, 0.55, 0.85), ("orange", "red", "white"),
               ("striped barrier", "road barrier", "barricade")),
    StaticKind("jersey barrier", (2.0, 0.6, 0.81), ("gray", "white", "orange"),
               ("concrete barrier", "k-rail", "jersey wall", "concrete block")),
    StaticKind("barrel", (0.6, 0.6, 1.0), ("orange", "yellow"), ("drum", "traffic barrel", "traffic drum")),
    StaticKind("stop sign", (0.12, 0.76, 2.6), ("red",)),
    StaticKind("speed limit sign", (0.12, 0.62, 2.5), ("white",), ("speed sign",)),
    StaticKind("parking sign", (0.12, 0.6, 2.45), ("blue",)),
    StaticKind("road work sign", (0.12, 0.9, 2.2), ("orange", "yellow"),
               ("road works sign", "construction sign", "warning sign", "men at work sign")),
    StaticKind("arrow board", (2.4, 1.8, 2.9), ("yellow", "orange"),
               ("arrow board trailer", "arrow trailer", "road works trailer", "flashing arrow")),
    StaticKind("excavator", (4.0, 2.0, 2.6), ("yellow", "orange"), ("digger", "backhoe", "construction machine")),
)}
#: Words for groups of kinds (``AssetSpec.subtype`` may name one): every member fits.
STATIC_GROUPS: dict[str, tuple[str, ...]] = {
    "barrier": ("barrier", "jersey barrier"),
    "sign": ("stop sign", "speed limit sign", "parking sign", "road work sign"),
    "construction equipment": ("arrow board", "excavator"),
    "road works": ("traffic cone", "barrier", "barrel", "road work sign", "arrow board"),
}


def static_subtype_for(word: str) -> str | None:
    """The procedural subtype a word names (its name or an alias, case-insensitive), or ``None``."""
    w = word.strip().lower()
    for kind in STATIC_KINDS.values():
        if w == kind.subtype or w in kind.aliases:
            return kind.subtype
    return None


# ---------------------------------------------------------------------------------------------- Gaussians
_R2 = (0.7548776662466927, 0.5698402909980532)  # Kronecker (R2) sequence: even cover of the unit square


def _triangle_samples(tris: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(points [S, 3], triangle [S])``: ``counts[m]`` evenly spread points on triangle ``m``."""
    tri_idx = np.repeat(np.arange(tris.shape[0]), counts)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    k = np.arange(tri_idx.size) - np.repeat(starts, counts) + 0.5  # sample number within its triangle
    u = np.mod(k * _R2[0] + 0.5, 1.0)
    v = np.mod(k * _R2[1] + 0.5, 1.0)
    flip = u + v > 1.0  # fold the unit square onto the triangle
    u, v = np.where(flip, 1.0 - u, u), np.where(flip, 1.0 - v, v)
    t = tris[tri_idx]
    points = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
    return points, tri_idx


def mesh_gaussians(mesh: Mesh, spacing: float, lighting: Lighting = ASSET_LIGHTING,
                   z_offset: float = 0.0) -> GaussianSet:
    """Flat Gaussian discs covering ``mesh``'s triangles, about ``spacing`` metres apart.

    Args:
        mesh: triangles in the object frame.
        spacing: target distance between neighbouring discs (metres).
        lighting: the lit colour of each face (``Lighting.shade``; emissive faces stay unlit).
        z_offset: added to every centre's z (``-h / 2`` moves a ground-based mesh into the box frame).
    Returns:
        a :class:`GaussianSet` of discs: radius ``DISC_RADIUS`` x the local spacing, thickness
        ``DISC_THICKNESS`` x the radius, opacity ``DISC_OPACITY``, rotated to the face normal.
    """
    if not len(mesh):
        raise ValueError("mesh_gaussians: the mesh has no triangles")
    edges1 = mesh.tris[:, 1] - mesh.tris[:, 0]
    edges2 = mesh.tris[:, 2] - mesh.tris[:, 0]
    area = 0.5 * np.linalg.norm(np.cross(edges1, edges2), axis=1)  # [M]
    keep = area > 1e-9
    tris, normals, colors, area = mesh.tris[keep], mesh.normals[keep], lighting.shade(mesh)[keep], area[keep]
    counts = np.maximum(1, np.ceil(area / spacing**2)).astype(np.int64)
    points, tri_idx = _triangle_samples(tris, counts)
    radius = DISC_RADIUS * np.minimum(spacing, np.sqrt(area / counts))[tri_idx]
    scales = np.stack([radius, radius, DISC_THICKNESS * radius], axis=1)
    points[:, 2] += z_offset
    t = lambda a: torch.as_tensor(np.asarray(a, dtype=np.float32))  # noqa: E731
    return GaussianSet.create(t(points), t(scales), t(np.clip(colors[tri_idx], 0.0, 1.0)), DISC_OPACITY,
                              quats=t(quats_from_normals(normals[tri_idx])))


def procedural_id(subtype: str, color: str) -> str:
    """``proc.<subtype with dashes>.<colour>``, e.g. ``proc.traffic-cone.orange``."""
    return f"proc.{subtype.replace(' ', '-')}.{color}"


def procedural_asset(subtype: str, color: str | None = None, size: tuple[float, float, float] | None = None,
                     asset_id: str | None = None) -> Asset:
    """A static asset of ``subtype`` in ``color`` (default: the kind's first colour) at ``size`` (default:
    the nominal size).

    Raises:
        ValueError: unknown subtype or colour, or a size outside ``RESIZE_RANGE`` of the nominal one.
    """
    kind = STATIC_KINDS.get(subtype)
    if kind is None:
        raise ValueError(f"unknown procedural static object {subtype!r}; known: {sorted(STATIC_KINDS)}")
    color = color or kind.colors[0]
    if color not in COLOR_NAMES:
        raise ValueError(f"unknown colour {color!r}; known: {list(COLOR_NAMES)}")
    dims = tuple(f32(v) for v in (size or kind.size))
    ratio = np.asarray(dims) / np.asarray(kind.size)
    if len(dims) != 3 or np.any(ratio < RESIZE_RANGE[0]) or np.any(ratio > RESIZE_RANGE[1]):
        raise ValueError(f"a {subtype} of size {dims} is outside {RESIZE_RANGE} x its nominal size {kind.size}")
    mesh = static_kind_mesh(subtype, (dims[0], dims[1], dims[2]), DISPLAY_RGB[color])
    spacing = max(MIN_SPACING_M, SPACING_SHARE * max(dims))
    gaussians = mesh_gaussians(mesh, spacing, z_offset=-dims[2] / 2.0)
    return Asset(asset_id=asset_id or procedural_id(subtype, color), category="static", subtype=subtype,
                 caption=caption_text("static", subtype, (color,)), color=color, size=(dims[0], dims[1], dims[2]),
                 source_seq="", source_object="", gaussians=gaussians, attributes={PROCEDURAL: subtype})


def procedural_assets() -> list[Asset]:
    """Every kind of ``STATIC_KINDS`` in each of its bank colours, at the nominal size."""
    out = [procedural_asset(kind.subtype, color) for kind in STATIC_KINDS.values() for color in kind.colors]
    logger.info("built %d procedural static assets (%d Gaussians)", len(out), sum(a.num_gaussians for a in out))
    return out


__all__ = ["ASSET_LIGHTING", "RESIZE_RANGE", "STATIC_GROUPS", "STATIC_KINDS", "StaticKind", "mesh_gaussians",
           "procedural_asset", "procedural_assets", "procedural_id", "static_kind_mesh", "static_subtype_for"]
