"""Initial scene graph of a ``SceneLog``: nodes from the tracks, Gaussians from depth or at random.

Nodes: background (id 0) plus one node per object, ids ``1..K`` in sorted ``object_id`` order; the
node type follows ``ObjectInfo.node_type`` (vehicles rigid, pedestrians non-rigid, static objects
rigid with the constant pose of their first track row). Object poses are the track boxes on the log's
frame axis.

**With depth** (every training image has ``depth``): each training pixel (``InitConfig.pixel_stride``) is
back-projected. Pixels whose instance id belongs to an object go to that node's box frame (inverse pose of
that frame); the rest go to the background. Without instance masks (lidar depth and 3D boxes: DGP) a point
belongs to the object whose box at that frame holds it (``InitConfig.box_margin``; the road under the box
stays background), so that the background does not learn the object and a removed car leaves with its node.
Points are merged in voxels (mean position and colour): background voxels are ``background_voxel_pixels``
pixel footprints at the distance of the nearest training camera (quantised to powers of two, so a
surface gets the same voxel size whichever view saw it), object voxels are a fixed size per object.
Pixels outside ``valid_mask`` and ``nan`` depth (no measurement) are skipped. **Sky** pixels (``+inf``
depth) become Gaussians on a dome of radius ``sky_radius`` around the scene
centre, merged in cells of ``sky_step_deg``: the dome is part of the background node and renders the
sky gradient of any view direction. **Sparse** depth (projected lidar: ``nan`` = no measurement) gives
every measured pixel, whatever the stride; it cannot tell sky apart, so the dome is then the random one
of the no-depth init, coloured from the images.

**Without depth**: background points on the ground around the ego path, on a shell (buildings) and on
the sky dome; object points uniform in their boxes; colours are looked up by projecting into the
training images (grey where no image sees a point).

**Shadows**: a vehicle or pedestrian node also starts with a shadow layer (:func:`shadow_layer`), dark
nearly transparent discs on the ground under and around its box, which training darkens where the
object's contact shadow falls.

Scales start isotropic at the 3DGS nearest-neighbour distance; rotations at identity; opacity at
``init_opacity``. Non-rigid offsets start at zero on the node's training frames.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.geometry import invert_transform
from simsplat_core.scene.config import InitConfig
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.knn import knn_scale
from simsplat_core.scene.nodes import (
    OFFSETS,
    BackgroundNode,
    NodeFields,
    NonRigidNode,
    PoseFields,
    RigidNode,
    SceneNode,
)
from simsplat_core.scene.transforms import poses_from_boxes
from simsplat_core.types import CameraImage, ObjectInfo, SceneLog, Track

logger = logging.getLogger(__name__)

_KEY_BITS = 20
_KEY_OFFSET = 1 << (_KEY_BITS - 1)


@dataclass
class PointCloud:
    """Points of one node in the node's frame.

    Attributes:
        points: ``[M, 3]``; rgb: ``[M, 3]`` in ``[0, 1]``;
        size: ``[M]`` voxel edge the point was merged at (0 = not merged, scale from kNN only);
        normals: ``[M, 3]`` surface normals (zero rows where unknown) or ``None``.
    """

    points: np.ndarray
    rgb: np.ndarray
    size: np.ndarray
    normals: np.ndarray | None = None

    @staticmethod
    def empty() -> PointCloud:
        return PointCloud(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3)))


# ---------------------------------------------------------------------------------------------- geometry
def scene_frame(log: SceneLog, train_images: list[CameraImage]) -> tuple[np.ndarray, float]:
    """``(center [3], scale)``: mean training camera position and 1.1x the largest distance to it (>= 1 m)."""
    centers = np.stack([img.cam_to_world[:3, 3] for img in train_images]) if train_images else log.ego_poses[:, :3, 3]
    center = centers.mean(axis=0)
    scale = max(1.1 * float(np.linalg.norm(centers - center, axis=1).max()), 1.0)
    return center, scale


def object_poses(log: SceneLog, obj: ObjectInfo, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(poses [F, 4, 4] float64, present [F] bool)`` of an object on the frame axis ``frames``."""
    track = log.track(obj.object_id)
    poses = np.tile(np.eye(4), (frames.size, 1, 1))
    present = np.zeros(frames.size, dtype=bool)
    pos = np.searchsorted(frames, track.frame_idx)
    ok = (pos < frames.size) & (frames[np.minimum(pos, frames.size - 1)] == track.frame_idx)
    box = poses_from_boxes(track.center, track.heading)
    if obj.node_type == "static" and len(track):
        box = np.repeat(box[:1], len(track), axis=0)
    poses[pos[ok]] = box[ok]
    present[pos[ok]] = True
    return poses, present


def _pixel_rays(img: CameraImage, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """``(ij [M, 2] pixel rows/cols, dirs [M, 3])`` world directions with unit camera z (ray t = z-depth)."""
    rows = np.arange(stride // 2, img.height, stride)
    cols = np.arange(stride // 2, img.width, stride)
    jj, ii = np.meshgrid(cols, rows)
    K = img.K
    x = (jj + 0.5 - K[0, 2]) / K[0, 0]
    y = (ii + 0.5 - K[1, 2]) / K[1, 1]
    d_cam = np.stack([x, y, np.ones_like(x)], axis=-1).reshape(-1, 3)
    return np.stack([ii.ravel(), jj.ravel()], axis=1), d_cam @ img.cam_to_world[:3, :3].T


def normal_map(img: CameraImage) -> np.ndarray:
    """``[H, W, 3]`` world-space surface normals from the depth map (central differences of the
    back-projected points, oriented towards the camera); zero where a neighbour is missing or across a
    depth discontinuity (relative jump above 5 %)."""
    if img.depth is None:
        raise ValueError(f"normal_map: frame {img.frame_idx} camera {img.camera!r} has no depth")
    _, dirs = _pixel_rays(img, 1)
    d = np.where(np.isfinite(img.depth), img.depth, 0.0).astype(np.float64)
    pts = (img.cam_to_world[:3, 3] + dirs * d.reshape(-1, 1)).reshape(img.height, img.width, 3)
    out = np.zeros_like(pts)
    n = np.cross(pts[1:-1, 2:] - pts[1:-1, :-2], pts[2:, 1:-1] - pts[:-2, 1:-1])
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    center = d[1:-1, 1:-1]
    neighbours = np.stack([d[1:-1, 2:], d[1:-1, :-2], d[2:, 1:-1], d[:-2, 1:-1]])
    smooth = np.all(np.abs(neighbours - center) <= 0.05 * center, axis=0) & (center > 0)
    n = np.where(smooth[..., None] & (norm > 0), n / np.maximum(norm, 1e-12), 0.0)
    view = dirs.reshape(img.height, img.width, 3)[1:-1, 1:-1]
    flip = np.sum(n * view, axis=-1, keepdims=True) > 0
    out[1:-1, 1:-1] = np.where(flip, -n, n)
    return out


def _group_mean(inverse: np.ndarray, counts: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``[G, D]`` mean of ``values [M, D]`` per group (``inverse [M]`` group of each row, ``counts [G]``)."""
    sums = np.stack([np.bincount(inverse, values[:, j], minlength=counts.size) for j in range(values.shape[1])], 1)
    return sums / counts[:, None]


def voxel_merge(points: np.ndarray, rgb: np.ndarray, size: np.ndarray, normals: np.ndarray | None = None
                ) -> PointCloud:
    """Average points (colours, normals) falling in the same voxel; ``size [M]`` is each point's voxel
    edge. Points with different sizes never merge (the size is part of the key), so callers quantise
    sizes. Merged normals are renormalised; they are zeroed where the members disagree (mean length
    below 0.5) or none was known.
    """
    if points.shape[0] == 0:
        return PointCloud.empty()
    idx = np.floor(points / size[:, None]).astype(np.int64) + _KEY_OFFSET
    if np.any(idx < 0) or np.any(idx >= (1 << _KEY_BITS)):
        raise ValueError("voxel_merge: coordinates out of the key range; increase the voxel size")
    _, size_code = np.unique(size, return_inverse=True)
    key = (size_code.astype(np.int64) << (3 * _KEY_BITS)) | (idx[:, 0] << (2 * _KEY_BITS)) | (idx[:, 1] << _KEY_BITS) \
        | idx[:, 2]
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    mean = lambda a: _group_mean(inverse, counts, a)  # noqa: E731
    out_size = np.zeros(counts.shape[0])
    out_size[inverse] = size
    out_normals = None
    if normals is not None:
        known = np.bincount(inverse, np.any(normals != 0, axis=1).astype(np.float64), minlength=counts.size)
        avg = mean(normals) * (counts / np.maximum(known, 1.0))[:, None]  # mean over members with a normal
        length = np.linalg.norm(avg, axis=1, keepdims=True)
        out_normals = np.where(length >= 0.5, avg / np.maximum(length, 1e-12), 0.0)
    return PointCloud(mean(points), mean(rgb), out_size, out_normals)


def _quantise_size(size: np.ndarray, smallest: float) -> np.ndarray:
    """Round sizes up to ``smallest * 2^k``."""
    level = np.ceil(np.log2(np.maximum(size, smallest) / smallest) - 1e-9)
    return smallest * np.power(2.0, level)


def _nearest_camera_distance(points: np.ndarray, cam_centers: np.ndarray, chunk: int = 1 << 20) -> np.ndarray:
    """``[M]`` distance from each point to the nearest of ``cam_centers [V, 3]``."""
    c = torch.from_numpy(cam_centers.astype(np.float32))
    out = np.empty(points.shape[0], dtype=np.float32)
    for s in range(0, points.shape[0], chunk):
        p = torch.from_numpy(points[s:s + chunk].astype(np.float32))
        out[s:s + chunk] = torch.cdist(p, c).min(dim=1).values.numpy()
    return out


# ---------------------------------------------------------------------------------------------- depth init
def _depth_samples(img: CameraImage, depth: np.ndarray, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """``(ij [M, 2], dirs [M, 3])`` pixels to back-project: the ``stride`` grid of a dense ``[H, W]`` depth map,
    every measured pixel of a sparse one (any ``nan``)."""
    if not np.isnan(depth).any():
        return _pixel_rays(img, stride)
    ij, dirs = _pixel_rays(img, 1)
    measured = np.isfinite(depth[ij[:, 0], ij[:, 1]])
    return ij[measured], dirs[measured]


def _sky_cloud(dirs: np.ndarray, rgb: np.ndarray, center: np.ndarray, cfg: InitConfig) -> PointCloud:
    """Sky pixels -> dome points merged in ``sky_step_deg`` cells (roughly equal area)."""
    if dirs.shape[0] == 0:
        return PointCloud.empty()
    unit = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    step = math.radians(cfg.sky_step_deg)
    el = np.arcsin(np.clip(unit[:, 2], -1.0, 1.0))
    az = np.arctan2(unit[:, 1], unit[:, 0])
    el_bin = np.floor(el / step).astype(np.int64)
    az_step = step / np.maximum(np.cos((el_bin + 0.5) * step), 0.05)
    az_bin = np.floor((az + np.pi) / az_step).astype(np.int64)
    key = (el_bin + 4096) * 1_000_000 + az_bin
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    mean = lambda a: _group_mean(inverse, counts, a)  # noqa: E731
    d = mean(unit)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pts = center[None] + cfg.sky_radius * d
    return PointCloud(pts, mean(rgb), np.full(pts.shape[0], cfg.sky_radius * step), -d)


def box_instances(points: np.ndarray, tracks: dict[int, Track], poses: dict[str, np.ndarray], frame_idx: int,
                  pos: int, cfg: InitConfig) -> np.ndarray:
    """``[M]`` int32 instance id of the object whose box (at frame ``frame_idx``, position ``pos`` of ``poses``,
    grown by ``cfg.box_margin`` but for its bottom, raised by ``cfg.box_ground_clearance``) holds each world
    point ``[M, 3]``; 0 for none, the nearest box centre where boxes overlap. ``tracks``: instance id -> track."""
    inst = np.zeros(points.shape[0], np.int32)
    best = np.full(points.shape[0], np.inf)
    for instance_id, track in tracks.items():
        rows = np.flatnonzero(track.frame_idx == frame_idx)
        if not rows.size:  # not in this frame
            continue
        half = 0.5 * np.asarray(track.size[rows[0]], np.float64)
        to_local = invert_transform(poses[track.object_id][pos])
        local = points @ to_local[:3, :3].T + to_local[:3, 3]
        inside = (np.abs(local[:, :2]) <= half[:2] + cfg.box_margin).all(axis=1) \
            & (local[:, 2] >= -half[2] + cfg.box_ground_clearance) & (local[:, 2] <= half[2] + cfg.box_margin)
        dist = np.linalg.norm(local, axis=1)
        take = inside & (dist < best)
        inst[take], best[take] = instance_id, dist[take]
    return inst


def depth_clouds(log: SceneLog, train_images: list[CameraImage], objects: list[ObjectInfo], frames: np.ndarray,
                 poses: dict[str, np.ndarray], center: np.ndarray, cfg: InitConfig
                 ) -> tuple[PointCloud, PointCloud, dict[str, PointCloud]]:
    """``(background, sky, {object_id: cloud in its box frame})`` from the depth of ``train_images``."""
    inst_to_obj = {o.instance_id: o for o in objects}
    tracks = {o.instance_id: log.track(o.object_id) for o in objects}  # for logs without instance masks
    bg_pts, bg_rgb, bg_nrm, sky_dirs, sky_rgb = [], [], [], [], []
    obj_parts: dict[str, list[tuple[np.ndarray, ...]]] = {o.object_id: [] for o in objects}
    for img in train_images:
        if img.depth is None or img.image is None:
            raise ValueError(f"depth_clouds: frame {img.frame_idx} camera {img.camera!r} needs pixels and depth")
        ij, dirs = _depth_samples(img, img.depth, cfg.pixel_stride)
        depth = img.depth[ij[:, 0], ij[:, 1]].astype(np.float64)
        rgb = img.image[ij[:, 0], ij[:, 1]].astype(np.float64)
        nrm = normal_map(img)[ij[:, 0], ij[:, 1]]
        valid = img.valid_mask[ij[:, 0], ij[:, 1]] if img.valid_mask is not None else np.ones(depth.shape, bool)
        finite = np.isfinite(depth) & (depth > 0) & valid
        sky = np.isposinf(depth) & valid  # nan = no measurement: neither surface nor sky
        sky_dirs.append(dirs[sky])
        sky_rgb.append(rgb[sky])
        pts = img.cam_to_world[:3, 3] + dirs[finite] * depth[finite, None]
        pos = int(np.searchsorted(frames, img.frame_idx))
        if img.instance is not None:
            inst_f = img.instance[ij[:, 0], ij[:, 1]][finite]
        else:  # no instance masks: an object's points are those in its box (else the background learns it)
            inst_f = box_instances(pts, tracks, poses, img.frame_idx, pos, cfg)
        rgb_f, nrm_f = rgb[finite], nrm[finite]
        footprint = depth[finite] / float(img.K[0, 0])
        is_obj = np.isin(inst_f, list(inst_to_obj)) if inst_to_obj else np.zeros(inst_f.shape, bool)
        bg_pts.append(pts[~is_obj])
        bg_rgb.append(rgb_f[~is_obj])
        bg_nrm.append(nrm_f[~is_obj])
        for iid in np.unique(inst_f[is_obj]):
            obj = inst_to_obj[int(iid)]
            sel = inst_f == iid
            to_local = invert_transform(poses[obj.object_id][pos])
            local = pts[sel] @ to_local[:3, :3].T + to_local[:3, 3]
            obj_parts[obj.object_id].append((local, rgb_f[sel], footprint[sel], nrm_f[sel] @ to_local[:3, :3].T))
    cam_centers = np.stack([img.cam_to_world[:3, 3] for img in train_images])
    fx = float(np.mean([img.K[0, 0] for img in train_images]))
    bg_p = np.concatenate(bg_pts) if bg_pts else np.zeros((0, 3))
    bg_c = np.concatenate(bg_rgb) if bg_rgb else np.zeros((0, 3))
    bg_n = np.concatenate(bg_nrm) if bg_nrm else np.zeros((0, 3))
    near = _nearest_camera_distance(bg_p, cam_centers)
    size = np.clip(cfg.background_voxel_pixels * near / fx, cfg.background_voxel_min, cfg.background_voxel_max)
    background = voxel_merge(bg_p, bg_c, _quantise_size(size, cfg.background_voxel_min), bg_n)
    sky = _sky_cloud(np.concatenate(sky_dirs), np.concatenate(sky_rgb), center, cfg)
    clouds = {}
    for oid, parts in obj_parts.items():
        if not parts:
            continue
        pts, rgb, footprint, nrm = (np.concatenate(arrays) for arrays in zip(*parts))
        voxel = float(np.clip(cfg.object_voxel_pixels * np.percentile(footprint, 20), cfg.object_voxel_min,
                              cfg.object_voxel_max))
        clouds[oid] = voxel_merge(pts, rgb, np.full(pts.shape[0], voxel), nrm)
    return background, sky, clouds


# ---------------------------------------------------------------------------------------------- random init
def colors_from_images(points: np.ndarray, images: list[CameraImage], max_images: int = 24) -> np.ndarray:
    """``[M, 3]`` colour of each world point from the first of (evenly chosen) ``images`` that sees it
    (grey 0.5 where none does)."""
    rgb = np.full((points.shape[0], 3), 0.5)
    done = np.zeros(points.shape[0], dtype=bool)
    usable = [img for img in images if img.image is not None]
    if not usable:
        return rgb
    pick = np.linspace(0, len(usable) - 1, min(max_images, len(usable))).round().astype(int)
    for k in pick:
        img = usable[k]
        w2c = invert_transform(img.cam_to_world)
        cam = points @ w2c[:3, :3].T + w2c[:3, 3]
        z = cam[:, 2]
        safe = np.where(z > 1e-3, z, 1.0)
        u = img.K[0, 0] * cam[:, 0] / safe + img.K[0, 2]
        v = img.K[1, 1] * cam[:, 1] / safe + img.K[1, 2]
        ok = (~done) & (z > 0.5) & (u >= 0) & (u < img.width) & (v >= 0) & (v < img.height)
        if img.valid_mask is not None:  # the ego car's body is not the colour of the scene behind it
            ok[ok] = img.valid_mask[v[ok].astype(int), u[ok].astype(int)]
        rgb[ok] = img.image[v[ok].astype(int), u[ok].astype(int)]
        done |= ok
    return rgb


def _sphere_points(center: np.ndarray, count: int, radius: float, min_el: float,
                   rng: np.random.Generator) -> np.ndarray:
    """``[count, 3]`` points uniform on the sphere cap above elevation ``min_el`` (radians) around ``center``."""
    az = rng.uniform(-np.pi, np.pi, count)
    el = np.arcsin(rng.uniform(np.sin(min_el), 1.0, count))
    return center + radius * np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=1)


def random_sky(train_images: list[CameraImage], center: np.ndarray, count: int, cfg: InitConfig,
               rng: np.random.Generator) -> PointCloud:
    """``count`` dome points (radius ``sky_radius``, down to 10 degrees below the horizon) coloured from the
    images."""
    sky = _sphere_points(center, count, cfg.sky_radius, math.radians(-10.0), rng)
    return PointCloud(sky, colors_from_images(sky, train_images), np.zeros(count))


def random_clouds(log: SceneLog, train_images: list[CameraImage], objects: list[ObjectInfo], center: np.ndarray,
                  cfg: InitConfig, rng: np.random.Generator) -> tuple[PointCloud, PointCloud, dict[str, PointCloud]]:
    """``(background, sky, {object_id: cloud})`` without depth (see the module docstring)."""
    ego = log.ego_poses[:, :3, 3]
    n = cfg.random_background_points
    n_ground, n_shell = n // 2, n // 4
    n_sky = n - n_ground - n_shell
    anchor = ego[rng.integers(0, ego.shape[0], n_ground)]
    r = cfg.random_ground_radius * np.sqrt(rng.random(n_ground))
    phi = rng.uniform(-np.pi, np.pi, n_ground)
    ground = anchor + np.stack([r * np.cos(phi), r * np.sin(phi), np.zeros(n_ground)], axis=1)

    shell = _sphere_points(center, n_shell, 1.5 * cfg.random_ground_radius, 0.0, rng)
    bg_pts = np.concatenate([ground, shell])
    background = PointCloud(bg_pts, colors_from_images(bg_pts, train_images), np.zeros(bg_pts.shape[0]))
    sky_cloud = random_sky(train_images, center, n_sky, cfg, rng)
    clouds = {}
    for obj in objects:
        track = log.track(obj.object_id)
        if not len(track):
            continue
        size = track.size[0]
        local = (rng.random((cfg.random_object_points, 3)) - 0.5) * size
        row = len(track) // 2
        world = local @ poses_from_boxes(track.center[row:row + 1], track.heading[row:row + 1])[0, :3, :3].T \
            + track.center[row]
        frame_images = [img for img in train_images if img.frame_idx == int(track.frame_idx[row])] or train_images
        clouds[obj.object_id] = PointCloud(local, colors_from_images(world, frame_images), np.zeros(local.shape[0]))
    return background, sky_cloud, clouds


# ---------------------------------------------------------------------------------------------- assembly
def quats_from_normals(normals: np.ndarray) -> np.ndarray:
    """``[M, 4]`` (w, x, y, z) rotations taking +z to each unit normal (identity for zero rows)."""
    n = np.asarray(normals, dtype=np.float64)
    known = np.linalg.norm(n, axis=1) > 0.5
    # shortest arc from z = (0, 0, 1): q = normalise(1 + n_z, -n_y, n_x, 0); antipodal -> 180 deg about x
    q = np.stack([1.0 + n[:, 2], -n[:, 1], n[:, 0], np.zeros(n.shape[0])], axis=1)
    flipped = known & (q[:, 0] < 1e-6)
    q[flipped] = [0.0, 1.0, 0.0, 0.0]
    q[~known] = [1.0, 0.0, 0.0, 0.0]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _gaussians(cloud: PointCloud, cfg: InitConfig, device: torch.device, max_scale: float) -> GaussianSet:
    """Gaussians at the cloud's points. Scale = kNN distance, kept within ``[0.3, 0.6]`` x the merge voxel
    where the points were voxel-merged (isolated points would get huge scales); points with a known
    normal become flat discs (``flat_ratio`` thickness) facing it."""
    scale = knn_scale(cloud.points, cfg.knn, min_scale=1e-3, max_scale=max_scale)
    merged = cloud.size > 0
    scale[merged] = np.clip(scale[merged], 0.3 * cloud.size[merged], 0.6 * cloud.size[merged])
    scales = np.repeat(scale[:, None], 3, axis=1)
    quats = None
    if cloud.normals is not None:
        known = np.linalg.norm(cloud.normals, axis=1) > 0.5
        scales[known, 2] *= cfg.flat_ratio
        quats = quats_from_normals(cloud.normals)
    t = lambda a: torch.as_tensor(np.asarray(a, dtype=np.float32), device=device)  # noqa: E731
    return GaussianSet.create(t(cloud.points), t(scales), t(np.clip(cloud.rgb, 0.0, 1.0)), cfg.init_opacity,
                              quats=None if quats is None else t(quats))


#: Categories whose nodes start with a shadow layer: objects that move and cast a contact shadow.
SHADOW_CATEGORIES: tuple[str, ...] = ("vehicle", "pedestrian")
_SHADOW_LIFT_M = 0.01  # the layer floats this far above the box bottom, in front of the road under it
_SHADOW_RGB = 0.02


def shadow_layer(size: np.ndarray, cfg: InitConfig, device: torch.device) -> GaussianSet | None:
    """The shadow layer of an object whose box is ``size [3]`` (length, width, height; box frame, z up):
    flat black discs ``shadow_spacing`` apart on the box's bottom plane, over its footprint grown by
    ``shadow_margin``, at opacity ``shadow_opacity``; ``None`` when ``shadow_spacing`` is 0.

    A black Gaussian of opacity ``a`` in front of the road multiplies the road's colour by ``1 - a``, which
    is what a shadow does to it; the layer is part of the object's node, so the shadow moves, is edited
    and is removed with the object."""
    if cfg.shadow_spacing <= 0:
        return None
    half = 0.5 * np.asarray(size[:2], dtype=np.float64) + cfg.shadow_margin
    counts = np.ceil(2.0 * half / cfg.shadow_spacing).astype(int) + 1  # at most shadow_spacing apart
    xs, ys = (np.linspace(-h, h, n) for h, n in zip(half, counts))
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    means = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, -0.5 * float(size[2]) + _SHADOW_LIFT_M)], axis=1)
    scales = np.tile([0.6 * cfg.shadow_spacing, 0.6 * cfg.shadow_spacing, 0.6 * cfg.shadow_spacing * cfg.flat_ratio],
                     (means.shape[0], 1))
    t = lambda a: torch.as_tensor(np.asarray(a, dtype=np.float32), device=device)  # noqa: E731
    return GaussianSet.create(t(means), t(scales), t(np.full((means.shape[0], 3), _SHADOW_RGB)), cfg.shadow_opacity)


def initial_graph(log: SceneLog, cfg: InitConfig, train_frames: set[int], seed: int = 0,
                  device: torch.device | str = "cpu") -> SceneGraph:
    """The initial scene graph of ``log`` (see the module docstring); ``train_frames`` are the frames
    whose images may be used (held-out frames and held-out views never are)."""
    device = torch.device(device)
    rng = np.random.default_rng(seed)
    frames = np.arange(log.num_frames, dtype=np.int64)
    train_images = [img for img in log.images if img.frame_idx in train_frames and img.split == "train"]
    objects = sorted(log.objects, key=lambda o: o.object_id)
    center, scene_scale = scene_frame(log, train_images)
    poses = {}
    present = {}
    for obj in objects:
        poses[obj.object_id], present[obj.object_id] = object_poses(log, obj, frames)
    has_depth = bool(train_images) and all(img.depth is not None and img.image is not None for img in train_images)
    if has_depth:
        background, sky, clouds = depth_clouds(log, train_images, objects, frames, poses, center, cfg)
        if sky.points.shape[0] == 0:
            sky = random_sky(train_images, center, cfg.random_background_points // 4, cfg, rng)
    else:
        background, sky, clouds = random_clouds(log, train_images, objects, center, cfg, rng)
    logger.info("init from %s: %d background, %d sky, %d object points", "depth" if has_depth else "random",
                background.points.shape[0], sky.points.shape[0], sum(c.points.shape[0] for c in clouds.values()))
    bg_gs = GaussianSet.cat([_gaussians(background, cfg, device, cfg.background_voxel_max),
                             _gaussians(sky, cfg, device, cfg.sky_radius * math.radians(4 * cfg.sky_step_deg))]) \
        if sky.points.shape[0] else _gaussians(background, cfg, device, cfg.background_voxel_max)
    nodes: list[SceneNode] = [BackgroundNode(node_id=0, gaussians=bg_gs, scale=scene_scale,
                                             center=(float(center[0]), float(center[1]), float(center[2])))]
    for node_id, obj in enumerate(objects, start=1):
        track = log.track(obj.object_id)
        size = track.size[0] if len(track) else np.ones(3)
        half_diag = float(0.5 * np.linalg.norm(size))
        cloud = clouds.get(obj.object_id)
        if cloud is None or cloud.points.shape[0] < 4:  # never seen in training: a few points in the box
            local = (rng.random((cfg.random_object_points, 3)) - 0.5) * size
            cloud = PointCloud(local, np.full((local.shape[0], 3), 0.5), np.zeros(local.shape[0]))
        gs = _gaussians(cloud, cfg, device, half_diag)
        shadow = shadow_layer(size, cfg, device) if obj.category in SHADOW_CATEGORIES else None
        if shadow is not None:
            gs = GaussianSet.cat([gs, shadow])
        common = NodeFields(node_id=node_id, gaussians=gs, object_id=obj.object_id, category=obj.category,
                            scale=half_diag)
        pose_kw = PoseFields(poses=torch.as_tensor(poses[obj.object_id], dtype=torch.float32, device=device),
                             present=torch.as_tensor(present[obj.object_id], device=device))
        if obj.node_type == "nonrigid":
            track_frames = frames[present[obj.object_id]]
            deform = np.array([f for f in track_frames if int(f) in train_frames] or track_frames, dtype=np.int64)
            gs.extras[OFFSETS] = torch.zeros((len(gs), deform.size, 3), device=device)
            nodes.append(NonRigidNode(**common, **pose_kw, deform_frames=deform))
        else:
            nodes.append(RigidNode(**common, **pose_kw, static=obj.node_type == "static"))
    metadata = {"seq_id": log.seq_id, "source": log.source, "init": "depth" if has_depth else "random"}
    return SceneGraph(frame_indices=frames, nodes=nodes, metadata=metadata)
