"""Triangle meshes of everything the renderer draws: vehicles, articulated pedestrians, static objects,
buildings and trees.

Meshes are built from convex *parts* (boxes, extruded polygons, frusta). Every triangle carries its
own three vertices (no sharing), a base colour, a material id and per-vertex texture coordinates, so
per-face attributes are trivial. Normals are made to point away from the part centroid, which is
correct because parts are convex.

Object meshes live in the object frame: x forward (heading), y left, z up, origin on the ground at
the box centre. ``Mesh.transformed`` places them in the world.

Material ids understood by ``raster.py``: ``MAT_PLAIN`` (procedural noise texture), ``MAT_FACADE``
(window grid from facade coordinates), ``MAT_SMOOTH`` (no texture: glass, lights), ``MAT_EMISSIVE``
(like smooth, but unlit by the sun: lamps).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.world.palette import NAMED_COLORS

MAT_PLAIN, MAT_FACADE, MAT_SMOOTH, MAT_EMISSIVE = 0, 1, 2, 3

GLASS = (0.2, 0.25, 0.31)
TIRE = (0.07, 0.07, 0.08)
HEADLIGHT = (0.98, 0.95, 0.8)
TAILLIGHT = (0.8, 0.05, 0.05)
PLASTIC = (0.12, 0.12, 0.13)


@dataclass(frozen=True)
class Mesh:
    """A triangle soup.

    Attributes:
        tris: ``[M, 3, 3]`` float64 vertex positions.
        normals: ``[M, 3]`` float64 unit outward normals.
        tex: ``[M, 3, 3]`` float32 per-vertex texture coordinates (object-frame positions, or
            ``(along-facade, 0, height)`` for ``MAT_FACADE``).
        color: ``[M, 3]`` float32 base RGB in ``[0, 1]``.
        material: ``[M]`` int32 material ids.
    """

    tris: np.ndarray
    normals: np.ndarray
    tex: np.ndarray
    color: np.ndarray
    material: np.ndarray

    def __len__(self) -> int:
        return int(self.tris.shape[0])

    @staticmethod
    def empty() -> Mesh:
        return Mesh(
            np.zeros((0, 3, 3)),
            np.zeros((0, 3)),
            np.zeros((0, 3, 3), np.float32),
            np.zeros((0, 3), np.float32),
            np.zeros(0, np.int32),
        )

    def transformed(self, rotation: np.ndarray, translation: np.ndarray) -> Mesh:
        """The mesh moved by ``p -> rotation @ p + translation`` (texture coordinates unchanged)."""
        return Mesh(
            self.tris @ rotation.T + translation, self.normals @ rotation.T, self.tex, self.color, self.material
        )

    @staticmethod
    def concat(meshes: list[Mesh]) -> Mesh:
        meshes = [m for m in meshes if len(m)]
        if not meshes:
            return Mesh.empty()
        return Mesh(
            np.concatenate([m.tris for m in meshes]),
            np.concatenate([m.normals for m in meshes]),
            np.concatenate([m.tex for m in meshes]),
            np.concatenate([m.color for m in meshes]),
            np.concatenate([m.material for m in meshes]),
        )


# ---------------------------------------------------------------------------------------------- parts
@dataclass
class Part:
    """A convex polyhedron: ``verts [V, 3]``, polygonal ``faces`` (index lists), per-face colour/material."""

    verts: np.ndarray
    faces: list[tuple[int, ...]]
    colors: list[tuple[float, float, float]]
    materials: list[int]
    facade: bool = False

    def moved(self, rotation: np.ndarray, pivot: np.ndarray, offset: np.ndarray | None = None) -> Part:
        """Rotate about ``pivot`` then translate by ``offset``."""
        v = (self.verts - pivot) @ rotation.T + pivot
        if offset is not None:
            v = v + offset
        return Part(v, self.faces, self.colors, self.materials, self.facade)


def _face_colors(color, n: int, overrides: dict[int, tuple] | None = None):
    cols = [tuple(color)] * n
    for k, c in (overrides or {}).items():
        cols[k] = tuple(c)
    return cols


def box(  # noqa: PLR0913 -- the six box bounds as scalars, then keyword options
    x0,
    x1,
    y0,
    y1,
    z0,
    z1,
    color,
    material=MAT_PLAIN,
    face_colors: dict[int, tuple] | None = None,
    face_mats: dict[int, int] | None = None,
    facade: bool = False,
) -> Part:
    """Axis-aligned box. Face order: -x, +x, -y, +y, -z, +z (indices for ``face_colors``/``face_mats``)."""
    xs, ys, zs = (x0, x1), (y0, y1), (z0, z1)
    verts = np.array([[xs[i & 1], ys[(i >> 1) & 1], zs[(i >> 2) & 1]] for i in range(8)], dtype=np.float64)
    faces: list[tuple[int, ...]] = [(0, 2, 6, 4), (1, 3, 7, 5), (0, 1, 5, 4), (2, 3, 7, 6), (0, 1, 3, 2), (4, 5, 7, 6)]
    mats = [material] * 6
    for k, m in (face_mats or {}).items():
        mats[k] = m
    return Part(verts, faces, _face_colors(color, 6, face_colors), mats, facade)


def extrude(
    poly: np.ndarray,
    axis: int,
    c0: float,
    c1: float,
    color,
    material=MAT_PLAIN,
    cap_color=None,
    side_colors: dict[int, tuple] | None = None,
    side_mats: dict[int, int] | None = None,
) -> Part:
    """Prism from a convex 2D polygon ``[P, 2]`` extruded along ``axis`` (0=x, 1=y, 2=z) from ``c0`` to ``c1``.

    The polygon's coordinates fill the two remaining axes in increasing order. Faces: cap at ``c0``,
    cap at ``c1``, then side ``i`` between polygon vertices ``i`` and ``i+1``.
    """
    p = len(poly)
    other = [a for a in range(3) if a != axis]
    verts = np.zeros((2 * p, 3))
    for k, c in enumerate((c0, c1)):
        verts[k * p : (k + 1) * p, other[0]] = poly[:, 0]
        verts[k * p : (k + 1) * p, other[1]] = poly[:, 1]
        verts[k * p : (k + 1) * p, axis] = c
    faces = [tuple(range(p)), tuple(range(p, 2 * p))] + [(i, (i + 1) % p, p + (i + 1) % p, p + i) for i in range(p)]
    cap = color if cap_color is None else cap_color
    colors = [tuple(cap), tuple(cap)] + [tuple(color)] * p
    mats = [material] * (p + 2)
    for k, side_color in (side_colors or {}).items():
        colors[2 + k] = tuple(side_color)
    for k, m in (side_mats or {}).items():
        mats[2 + k] = m
    return Part(verts, faces, colors, mats)


def frustum(n: int, r0: float, r1: float, z0: float, z1: float, color, material=MAT_PLAIN, phase: float = 0.0) -> Part:
    """Vertical truncated pyramid with an ``n``-gon cross-section, radius ``r0`` at ``z0`` and ``r1`` at ``z1``."""
    ang = phase + 2 * np.pi * np.arange(n) / n
    ring = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    verts = np.concatenate(
        [
            np.concatenate([ring * r0, np.full((n, 1), z0)], 1),
            np.concatenate([ring * max(r1, 1e-3), np.full((n, 1), z1)], 1),
        ]
    )
    faces = [tuple(range(n)), tuple(range(n, 2 * n))] + [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    return Part(verts, faces, [tuple(color)] * (n + 2), [material] * (n + 2))


def rot_y(angle: float) -> np.ndarray:
    """Rotation about +y; positive angles swing -z (downward limbs) towards +x (forward)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def parts_to_mesh(parts: list[Part]) -> Mesh:
    """Fan-triangulate parts into a ``Mesh`` with outward normals."""
    tris, normals, tex, colors, mats = [], [], [], [], []
    for part in parts:
        centroid = part.verts.mean(axis=0)
        for face, col, mat in zip(part.faces, part.colors, part.materials):
            fv = part.verts[list(face)]
            n = np.cross(fv[1] - fv[0], fv[2] - fv[0])
            norm = np.linalg.norm(n)
            if norm < 1e-12:
                n = np.cross(fv[2] - fv[0], fv[3] - fv[0]) if len(fv) > 3 else n
                norm = np.linalg.norm(n)
                if norm < 1e-12:
                    continue
            n = n / norm
            if np.dot(n, fv.mean(axis=0) - centroid) < 0:
                n = -n
            if part.facade and abs(n[2]) < 0.5:
                t = np.array([-n[1], n[0], 0.0])
                t /= np.linalg.norm(t)
                ftex = np.stack([fv @ t, np.zeros(len(fv)), fv[:, 2]], axis=1)
                fmat = MAT_FACADE
            else:
                ftex = fv
                fmat = MAT_PLAIN if mat == MAT_FACADE else mat
            for k in range(1, len(face) - 1):
                tris.append(fv[[0, k, k + 1]])
                tex.append(ftex[[0, k, k + 1]])
                normals.append(n)
                colors.append(col)
                mats.append(fmat)
    if not tris:
        return Mesh.empty()
    return Mesh(
        np.asarray(tris, dtype=np.float64),
        np.asarray(normals, dtype=np.float64),
        np.asarray(tex, dtype=np.float32),
        np.asarray(colors, dtype=np.float32),
        np.asarray(mats, dtype=np.int32),
    )


# ---------------------------------------------------------------------------------------------- vehicles
#: Cabin profile per body style: (belt height / H, cabin bottom x0, x1, top x0, x1) as fractions of L.
_CABINS = {
    "sedan": (0.56, -0.30, 0.17, -0.21, 0.02),
    "hatchback": (0.56, -0.47, 0.15, -0.43, 0.00),
    "SUV": (0.56, -0.47, 0.20, -0.45, 0.05),
    "van": (0.46, -0.496, 0.30, -0.496, 0.17),  # rear face kept inside the body-coloured rear wall
    "pickup truck": (0.56, -0.08, 0.24, -0.07, 0.12),
}


def _wheels(length: float, width: float, radius: float, axles: tuple[float, ...]) -> list[Part]:
    ang = np.pi / 8 + 2 * np.pi * np.arange(8) / 8
    poly = np.stack([np.cos(ang), np.sin(ang)], axis=1) * radius
    parts = []
    for ax in axles:
        for side in (-1.0, 1.0):
            y_out = side * (width / 2.0 - 0.02)
            y_in = side * (width / 2.0 - 0.27)
            wheel = extrude(poly + np.array([ax, radius]), 1, min(y_in, y_out), max(y_in, y_out), TIRE, MAT_SMOOTH)
            parts.append(wheel)
    return parts


def _lights(length: float, width: float, z0: float, z1: float) -> list[Part]:
    parts = []
    for side in (-1.0, 1.0):
        ya, yb = sorted((side * (width / 2.0 - 0.12), side * (width / 2.0 - 0.42)))
        parts.append(box(length / 2.0 - 0.02, length / 2.0 + 0.01, ya, yb, z0, z1, HEADLIGHT, MAT_EMISSIVE))
        parts.append(box(-length / 2.0 - 0.01, -length / 2.0 + 0.02, ya, yb, z0, z1, TAILLIGHT, MAT_EMISSIVE))
    return parts


def vehicle_mesh(subtype: str, size: tuple[float, float, float], color: tuple[float, float, float]) -> Mesh:
    """Mesh of a vehicle of ``subtype`` filling the box ``size = (L, W, H)`` (object frame)."""
    L, W, H = size
    col = tuple(color)
    parts: list[Part] = []
    if subtype in _CABINS:
        belt, bx0, bx1, tx0, tx1 = _CABINS[subtype]
        r = 0.33 if subtype in ("sedan", "hatchback") else 0.38
        zb = belt * H
        parts.append(box(-L / 2, L / 2, -W / 2, W / 2, 0.7 * r, zb, col))
        inset = 0.09
        prof = np.array([[bx0 * L, zb], [bx1 * L, zb], [tx1 * L, H], [tx0 * L, H]])
        # side faces: 0 bottom, 1 windshield, 2 roof, 3 rear window; caps are the side windows
        parts.append(
            extrude(
                prof,
                1,
                -W / 2 + inset,
                W / 2 - inset,
                GLASS,
                MAT_SMOOTH,
                cap_color=GLASS,
                side_colors={0: col, 2: col},
                side_mats={0: MAT_PLAIN, 2: MAT_PLAIN},
            )
        )
        if subtype == "van":
            # body-coloured rear half of the side walls
            parts.append(box(-L / 2, bx0 * L + 0.45 * L, -W / 2 + inset - 0.01, W / 2 - inset + 0.01, zb, H, col))
        parts += _wheels(L, W, r, (0.31 * L, -0.31 * L))
        parts += _lights(L, W, zb - 0.22, zb - 0.08)
    elif subtype == "truck":
        cab = 2.2
        parts.append(box(L / 2 - cab, L / 2, -W / 2, W / 2, 0.45, 1.45, col))
        prof = np.array([[L / 2 - cab, 1.45], [L / 2 - 0.05, 1.45], [L / 2 - 0.45, 2.75], [L / 2 - cab, 2.75]])
        parts.append(
            extrude(
                prof,
                1,
                -W / 2 + 0.05,
                W / 2 - 0.05,
                GLASS,
                MAT_SMOOTH,
                cap_color=col,
                side_colors={0: col, 2: col, 3: col},
                side_mats={0: MAT_PLAIN, 2: MAT_PLAIN, 3: MAT_PLAIN},
            )
        )
        parts.append(box(-L / 2, L / 2 - cab - 0.15, -W / 2, W / 2, 0.95, H, col))
        parts.append(box(-L / 2 + 0.3, L / 2 - cab, -W / 2 + 0.25, W / 2 - 0.25, 0.45, 0.95, PLASTIC))
        parts += _wheels(L, W, 0.5, (L / 2 - 1.3, -L / 2 + 1.6))
        parts += _lights(L, W, 0.75, 0.95)
    elif subtype == "bus":
        parts.append(box(-L / 2, L / 2, -W / 2, W / 2, 0.35, 1.15, col))
        parts.append(
            box(-L / 2, L / 2, -W / 2 + 0.01, W / 2 - 0.01, 1.15, 2.45, GLASS, MAT_SMOOTH, face_colors={4: col, 5: col})
        )
        parts.append(box(-L / 2, L / 2, -W / 2, W / 2, 2.45, H, col))
        parts += _wheels(L, W, 0.5, (L / 2 - 2.6, -L / 2 + 3.0))
        parts += _lights(L, W, 0.55, 0.8)
    else:
        raise ValueError(f"unknown vehicle subtype {subtype!r}")
    return parts_to_mesh(parts)


# ---------------------------------------------------------------------------------------------- pedestrians
#: Joint groups of the articulated pedestrian: (name, side, is_arm).
_JOINTS = (("left_leg", 1.0, False), ("right_leg", -1.0, False), ("left_arm", 1.0, True), ("right_arm", -1.0, True))


def _pedestrian_rest(height: float, upper, lower, skin, hair) -> tuple[list[Part], list[int], list[np.ndarray]]:
    """Rest-pose parts, the joint group of each part (-1 = rigid body) and each group's pivot."""
    h = height
    sc = h / 1.75
    hip = 0.48 * h
    shoulder = 0.81 * h
    parts: list[Part] = [
        box(-0.1 * sc, 0.1 * sc, -0.17 * sc, 0.17 * sc, hip - 0.06 * sc, hip + 0.1 * sc, lower),
        box(-0.11 * sc, 0.11 * sc, -0.19 * sc, 0.19 * sc, hip + 0.1 * sc, shoulder, upper),
        box(-0.05 * sc, 0.05 * sc, -0.05 * sc, 0.05 * sc, shoulder, 0.875 * h, skin),
        box(-0.095 * sc, 0.095 * sc, -0.085 * sc, 0.085 * sc, 0.875 * h, 0.965 * h, skin, face_colors={0: hair}),
        box(-0.105 * sc, 0.095 * sc, -0.09 * sc, 0.09 * sc, 0.965 * h, h, hair),
    ]
    groups = [-1] * len(parts)
    pivots: list[np.ndarray] = []
    for g, (_, side, is_arm) in enumerate(_JOINTS):
        if not is_arm:
            y = side * 0.095 * sc
            pivots.append(np.array([0.0, y, hip]))
            parts += [
                box(-0.07 * sc, 0.07 * sc, y - 0.075 * sc, y + 0.075 * sc, 0.07 * sc, hip, lower),
                box(-0.075 * sc, 0.105 * sc, y - 0.07 * sc, y + 0.07 * sc, 0.0, 0.07 * sc, PLASTIC),
            ]
        else:
            y = side * 0.245 * sc
            pivots.append(np.array([0.0, y, shoulder - 0.04 * sc]))
            parts += [
                box(-0.05 * sc, 0.05 * sc, y - 0.05 * sc, y + 0.05 * sc, shoulder - 0.3 * h, shoulder, upper),
                box(
                    -0.045 * sc,
                    0.045 * sc,
                    y - 0.045 * sc,
                    y + 0.045 * sc,
                    shoulder - 0.37 * h,
                    shoulder - 0.3 * h,
                    skin,
                ),
            ]
        groups += [g, g]
    return parts, groups, pivots


def joint_angles(phase: float, swing: float) -> np.ndarray:
    """``[4]`` joint angles (left leg, right leg, left arm, right arm) at gait ``phase``; legs swing in
    anti-phase, each arm opposite to the leg on its side at 0.8x amplitude."""
    theta = swing * np.sin(phase)
    return np.array([theta, -theta, -0.8 * theta, 0.8 * theta])


class PedestrianRig:
    """Articulated pedestrian: torso, head, two legs and two arms rotating about hip/shoulder joints.

    The rest-pose mesh is triangulated once; ``mesh(phase)`` rotates the four limb groups. Texture
    coordinates stay those of the rest pose, so the texture sticks to the limbs.
    """

    def __init__(self, height: float, swing: float, upper, lower, skin, hair) -> None:
        parts, groups, pivots = _pedestrian_rest(height, upper, lower, skin, hair)
        meshes = [parts_to_mesh([p]) for p in parts]
        self.rest = Mesh.concat(meshes)
        self.group = np.concatenate([np.full(len(m), g) for m, g in zip(meshes, groups)])
        self.pivots = pivots
        self.swing = swing
        self.height = height

    def mesh(self, phase: float) -> Mesh:
        """Posed mesh ``[M]`` triangles at gait ``phase`` (radians)."""
        tris = self.rest.tris.copy()
        normals = self.rest.normals.copy()
        for g, angle in enumerate(joint_angles(phase, self.swing)):
            if angle == 0.0:
                continue
            sel = self.group == g
            rot = rot_y(float(angle))
            tris[sel] = (tris[sel] - self.pivots[g]) @ rot.T + self.pivots[g]
            normals[sel] = normals[sel] @ rot.T
        return Mesh(tris, normals, self.rest.tex, self.rest.color, self.rest.material)


def pedestrian_mesh(height: float, phase: float, swing: float, upper, lower, skin, hair) -> Mesh:
    """Articulated pedestrian mesh at walk ``phase`` (radians); ``swing`` is the peak leg angle."""
    return PedestrianRig(height, swing, upper, lower, skin, hair).mesh(phase)


def pedestrian_extent(height: float, swing: float) -> tuple[float, float, float]:
    """Tight box ``(length, width, height)`` containing the pedestrian over its whole gait cycle."""
    gray = (0.5, 0.5, 0.5)
    rig = PedestrianRig(height, swing, gray, gray, gray, gray)
    ext = np.zeros(2)
    for phase in np.linspace(0.0, 2 * np.pi, 33):
        pts = rig.mesh(phase).tris.reshape(-1, 3)
        ext = np.maximum(ext, np.abs(pts[:, :2]).max(axis=0))
    return float(2 * ext[0] + 0.01), float(2 * ext[1] + 0.01), float(height)


# ---------------------------------------------------------------------------------------------- static objects
def static_mesh(subtype: str, size: tuple[float, float, float], color: tuple[float, float, float]) -> Mesh:
    """Mesh of a static object (traffic cone, barrier, stop/speed limit/parking sign) in the object frame."""
    L, W, H = size
    col = tuple(color)
    white = NAMED_COLORS["white"]
    parts: list[Part] = []
    if subtype == "traffic cone":
        parts.append(box(-L / 2, L / 2, -W / 2, W / 2, 0.0, 0.04, PLASTIC))
        r0 = 0.42 * min(L, W)
        for z0, z1, c in ((0.04, 0.42 * H, col), (0.42 * H, 0.62 * H, white), (0.62 * H, H, col)):
            f0 = r0 * (1 - (z0 - 0.04) / (H - 0.04) * 0.85)
            f1 = r0 * (1 - (z1 - 0.04) / (H - 0.04) * 0.85)
            parts.append(frustum(8, f0, f1, z0, z1, c, phase=np.pi / 8))
    elif subtype == "barrier":
        prof = np.array([[-W / 2, 0.0], [W / 2, 0.0], [W / 4, 0.3 * H], [W / 6, H], [-W / 6, H], [-W / 4, 0.3 * H]])
        n_seg = 4
        edges = np.linspace(-L / 2, L / 2, n_seg + 1)
        for k in range(n_seg):
            c = col if k % 2 == 0 or col == white else white
            parts.append(extrude(prof, 0, edges[k], edges[k + 1], c))
    elif subtype in ("stop sign", "speed limit sign", "parking sign"):
        gray = (0.55, 0.56, 0.58)
        parts.append(box(-L / 2, -L / 2 + 0.07, -0.035, 0.035, 0.0, H - 0.15, gray))
        if subtype == "stop sign":
            r = W / 2
            ang = np.pi / 8 + 2 * np.pi * np.arange(8) / 8
            poly = np.stack([np.cos(ang) * r, np.sin(ang) * r + H - r], axis=1)
            parts.append(extrude(poly, 0, -L / 2 + 0.07, L / 2, col, cap_color=col))
        else:
            panel_h = 0.75 if subtype == "speed limit sign" else W
            parts.append(box(-L / 2 + 0.07, L / 2, -W / 2, W / 2, H - panel_h, H, col, face_colors={0: gray}))
            # a dark emblem so the sign reads as a sign
            emb = (0.05, 0.05, 0.05) if subtype == "speed limit sign" else white
            parts.append(
                box(L / 2 - 0.005, L / 2 + 0.005, -W / 5, W / 5, H - 0.7 * panel_h, H - 0.3 * panel_h, emb, MAT_SMOOTH)
            )
    else:
        raise ValueError(f"unknown static subtype {subtype!r}")
    return parts_to_mesh(parts)


# ---------------------------------------------------------------------------------------------- scenery
def building_mesh(x0: float, x1: float, y0: float, y1: float, height: float, color) -> Mesh:
    """Axis-aligned building block (world frame) with a window-grid facade and a flat grey roof."""
    roof = (0.42, 0.42, 0.44)
    return parts_to_mesh([box(x0, x1, y0, y1, 0.0, height, color, face_colors={5: roof}, facade=True)])


def tree_mesh(x: float, y: float, height: float, radius: float, leaf) -> Mesh:
    """A tree (world frame): a brown trunk and a faceted green crown."""
    trunk = (0.35, 0.25, 0.15)
    parts = [
        box(x - 0.12, x + 0.12, y - 0.12, y + 0.12, 0.0, 0.45 * height, trunk),
        frustum(7, radius, radius * 0.85, 0.4 * height, 0.75 * height, leaf).moved(
            np.eye(3), np.zeros(3), np.array([x, y, 0.0])
        ),
        frustum(7, radius * 0.85, 0.15, 0.75 * height, height, leaf).moved(
            np.eye(3), np.zeros(3), np.array([x, y, 0.0])
        ),
    ]
    return parts_to_mesh(parts)
