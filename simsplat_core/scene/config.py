"""``ReconstructionConfig`` and its parts (frozen dataclasses, validated on construction).

Every validation error names the offending field as ``ReconstructionConfig.<part>.<field>``.
Defaults are tuned for the synthetic demo sequence (40 frames, 3 cameras at 240x160) on a 2-core CPU;
``bench/bench_reconstruct.py`` measures them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from simsplat_core.render.types import BACKENDS


class ConfigError(ValueError):
    """An invalid configuration value; the message names the field."""


def _check(cond: bool, name: str, message: str, value: object) -> None:
    if not cond:
        raise ConfigError(f"{name} {message}, got {value!r}")


def _positive(obj: object, prefix: str, names: tuple[str, ...], allow_zero: bool = False) -> None:
    for name in names:
        value = getattr(obj, name)
        ok = isinstance(value, (int, float)) and math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
        _check(ok, f"{prefix}.{name}", "must be >= 0" if allow_zero else "must be > 0", value)


@dataclass(frozen=True)
class ParamLRs:
    """Adam learning rates of one node type, per parameter.

    ``means`` is in units of the node's scale (scene radius for the background, box half-diagonal for
    objects) and decays exponentially to ``means * LearningRates.means_final_factor`` at the last step.
    """

    means: float = 1.6e-4
    log_scales: float = 5e-3
    quats: float = 1e-3
    colors: float = 1e-2
    opacity_logits: float = 5e-2
    features: float = 1e-3
    offsets: float = 2e-3
    pose_deltas: float = 1e-4

    def validate(self, prefix: str) -> None:
        _positive(self, prefix, tuple(f.name for f in fields(self)), allow_zero=True)

    def get(self, name: str) -> float:
        return float(getattr(self, name))


@dataclass(frozen=True)
class LearningRates:
    """Per node type learning rates (``static`` objects use ``rigid`` unless given)."""

    background: ParamLRs = field(default_factory=ParamLRs)
    rigid: ParamLRs = field(default_factory=ParamLRs)
    nonrigid: ParamLRs = field(default_factory=ParamLRs)
    static: ParamLRs = field(default_factory=ParamLRs)
    means_final_factor: float = 0.01

    def validate(self, prefix: str) -> None:
        for name in ("background", "rigid", "nonrigid", "static"):
            getattr(self, name).validate(f"{prefix}.{name}")
        _check(0 < self.means_final_factor <= 1, f"{prefix}.means_final_factor", "must be in (0, 1]",
               self.means_final_factor)

    def for_type(self, node_type: str) -> ParamLRs:
        return getattr(self, node_type)


@dataclass(frozen=True)
class DensifyConfig:
    """Adaptive density control (gsplat's default strategy, see :mod:`simsplat_core.scene.densify`).

    Attributes:
        enabled: run densification at all.
        refine_start, refine_every: first step and period of refinement.
        refine_stop_fraction: no refinement after this fraction of the iterations.
        grad_threshold: mean screen-space gradient (gsplat's normalisation) above which a Gaussian grows.
        grow_scale3d: grown Gaussians larger than this fraction of their node's scale split, others clone.
        split_factor: scale divisor of the two children of a split (gsplat: 1.6).
        prune_opacity: Gaussians below this opacity are pruned at every refinement.
        prune_scale3d: Gaussians larger than this fraction of ``max(node scale, distance to the node
            centre)`` are pruned (distance-relative, so the far sky dome is not culled).
        reset_every: period of the opacity reset (0 = never); resets to ``2 * prune_opacity``.
        max_gaussians: growth stops when the scene has this many Gaussians.
    """

    enabled: bool = True
    refine_start: int = 200
    refine_every: int = 100
    refine_stop_fraction: float = 0.6
    grad_threshold: float = 2e-4
    grow_scale3d: float = 0.01
    split_factor: float = 1.6
    prune_opacity: float = 0.005
    prune_scale3d: float = 0.5
    reset_every: int = 0
    max_gaussians: int = 150_000

    def validate(self, prefix: str) -> None:
        _positive(self, prefix, ("refine_every", "grad_threshold", "grow_scale3d", "split_factor", "prune_scale3d",
                                 "max_gaussians"))
        _positive(self, prefix, ("refine_start", "reset_every", "prune_opacity"), allow_zero=True)
        _check(0 <= self.refine_stop_fraction <= 1, f"{prefix}.refine_stop_fraction", "must be in [0, 1]",
               self.refine_stop_fraction)
        _check(self.prune_opacity < 1, f"{prefix}.prune_opacity", "must be < 1", self.prune_opacity)


@dataclass(frozen=True)
class LossWeights:
    """Loss terms: ``(1 - dssim) L1_w + dssim D-SSIM + depth L1(inverse depth) + regularisers``.

    Attributes:
        dssim: lambda of the D-SSIM term (3DGS convention, 0.2).
        object_weight: the L1 term weights pixels of objects (ground-truth instance mask, where the log
            has one) this much more than the rest; objects are small in the image and the scene is judged
            on them too (1 = plain L1).
        object_mask: weight of an L1 loss between the rendered object coverage (composited indicator of the
            bodies of object nodes: their Gaussians above ``InitConfig.box_ground_clearance``, not their shadow
            layers) and the ground-truth object mask (instance > 0) where the log has
            instance masks: objects become opaque inside their silhouettes, the background stops
            covering them, and object nodes stop painting background colour around themselves (without
            it a pedestrian's node fills the gap between its legs with sidewalk-coloured Gaussians and
            its projected mask loses ~25% precision; 0 = off). Measured on the default sequence, 900
            steps: 0.5 keeps test PSNR within 0.2 dB and raises the node masks' mean vIoU against the
            instance masks from ~0.80 to ~0.89; 1.0 and 2.0 raise it further but cost the dynamic PSNR.
        depth: weight of an L1 loss on inverse expected depth where the log has finite depth (0 = off).
        deform_smooth: weight of ``mean_n sum_t |o_{t+1} - o_t|^2`` over non-rigid offsets (velocity).
        deform_accel: weight of ``mean_n sum_t |o_{t+1} - 2 o_t + o_{t-1}|^2`` (temporal smoothness: held-out
            frames are interpolated between trained ones, so offsets should move nearly linearly).
        deform_magnitude: weight of ``mean_n sum_t |o_t|^2`` (keeps the canonical shape meaningful).
        pose_delta: weight of ``mean |delta|^2`` on pose refinements.
    """

    dssim: float = 0.2
    object_weight: float = 10.0
    object_mask: float = 0.5
    depth: float = 0.0
    deform_smooth: float = 0.0
    deform_accel: float = 0.1
    deform_magnitude: float = 0.001
    pose_delta: float = 1.0

    def validate(self, prefix: str) -> None:
        _check(0 <= self.dssim <= 1, f"{prefix}.dssim", "must be in [0, 1]", self.dssim)
        _positive(self, prefix, ("object_mask", "depth", "deform_smooth", "deform_accel", "deform_magnitude",
                                 "pose_delta"), allow_zero=True)
        _check(self.object_weight >= 1, f"{prefix}.object_weight", "must be >= 1", self.object_weight)


@dataclass(frozen=True)
class InitConfig:
    """Initialisation of the Gaussians (see :mod:`simsplat_core.scene.init`).

    Attributes:
        pixel_stride: back-project every ``pixel_stride``-th pixel in x and y (depth logs).
        background_voxel_pixels: background points are merged in voxels of this many pixel footprints
            at the distance of the nearest training camera.
        background_voxel_min, background_voxel_max: voxel size bounds (metres) of the background.
        object_voxel_pixels: object points are merged in voxels of this many (20th percentile) pixel
            footprints of that object's observations.
        object_voxel_min, object_voxel_max: voxel size bounds (metres) of objects.
        sky_radius: radius (metres) of the sky dome around the scene centre (sky pixels and random init).
        sky_step_deg: angular size of the sky dome's cells.
        init_opacity: initial opacity of every Gaussian.
        flat_ratio: depth-initialised points with a surface normal start as discs this thin (relative).
        random_background_points: number of random background points without depth (ground + shell).
        random_object_points: random points per object without depth (uniform in its box).
        random_ground_radius: radius (metres) around the ego path of the random ground points.
        knn: neighbours averaged for the initial scale (``sqrt(mean d^2)`` of the ``knn`` nearest).
        box_margin: without instance masks (lidar depth and 3D boxes), a depth point within this many metres
            of an object's box at that frame belongs to the object ...
        box_ground_clearance: ... unless it lies less than this above the box's bottom (the road under and
            around it stays background). The same height splits an object node's Gaussians into its body and
            its shadow layer (below it), which the object-coverage loss leaves out.
        shadow_spacing: a moving object (vehicle or pedestrian) starts with a layer of dark, nearly transparent
            flat Gaussians this far apart on the ground under and around its box. A contact shadow moves with
            the object: without a layer of its own the background learns it as dark smudges wherever the
            object has been, and a removed object leaves its shadow behind (0 = no layer).
        shadow_margin: the layer reaches this far beyond the box's footprint on every side (metres).
        shadow_opacity: initial opacity of the layer's Gaussians (they start black).
    """

    pixel_stride: int = 1
    background_voxel_pixels: float = 4.0
    background_voxel_min: float = 0.05
    background_voxel_max: float = 8.0
    object_voxel_pixels: float = 1.5
    object_voxel_min: float = 0.02
    object_voxel_max: float = 0.25
    sky_radius: float = 1000.0
    sky_step_deg: float = 1.5
    init_opacity: float = 0.5
    flat_ratio: float = 0.2
    random_background_points: int = 30_000
    random_object_points: int = 300
    random_ground_radius: float = 40.0
    knn: int = 3
    box_margin: float = 0.2
    box_ground_clearance: float = 0.15
    shadow_spacing: float = 0.15
    shadow_margin: float = 0.3
    shadow_opacity: float = 0.05

    def validate(self, prefix: str) -> None:
        _check(self.box_margin >= 0, f"{prefix}.box_margin", "must be >= 0", self.box_margin)
        _check(self.box_ground_clearance >= 0, f"{prefix}.box_ground_clearance", "must be >= 0",
               self.box_ground_clearance)
        _positive(self, prefix, ("shadow_spacing", "shadow_margin"), allow_zero=True)
        _check(0 < self.shadow_opacity < 1, f"{prefix}.shadow_opacity", "must be in (0, 1)", self.shadow_opacity)
        _positive(self, prefix, ("pixel_stride", "background_voxel_pixels", "background_voxel_min",
                                 "background_voxel_max", "object_voxel_pixels", "object_voxel_min",
                                 "object_voxel_max", "sky_radius", "sky_step_deg", "random_background_points",
                                 "random_object_points", "random_ground_radius", "knn", "flat_ratio"))
        _check(0 < self.init_opacity < 1, f"{prefix}.init_opacity", "must be in (0, 1)", self.init_opacity)
        _check(self.background_voxel_min <= self.background_voxel_max, f"{prefix}.background_voxel_max",
               "must be >= background_voxel_min", self.background_voxel_max)
        _check(self.object_voxel_min <= self.object_voxel_max, f"{prefix}.object_voxel_max",
               "must be >= object_voxel_min", self.object_voxel_max)


DEVICES: tuple[str, ...] = ("auto", "cpu", "cuda")


@dataclass(frozen=True)
class ReconstructionConfig:
    """Everything ``reconstruct`` needs besides the log.

    Attributes:
        iterations: optimisation steps (one training frame per step).
        cameras_per_step: cameras of that frame rendered per step (random subset when fewer than all).
        lr, densify, loss, init: the parts above.
        deform_holdout: probability per step that non-rigid offsets at the training frame are replaced by
            the interpolation of the neighbouring trained frames (``SceneGraph.at(holdout_offsets=True)``);
            held-out frames are rendered by that interpolation, so this trains what they see.
        eps2d: screen-space low-pass of the rasterizer (pixels^2, gsplat uses 0.3); kept with the scene
            (``SceneGraph.eps2d``). Smaller values let Gaussians form sharper edges, which pays off
            against aliased ground truth (measured +0.6 dB test PSNR on the synthetic demo with 0.1).
        refine_poses: learn a small SE(3) correction per object and frame on top of the track poses
            (off by default: synthetic tracks are exact; useful for real logs).
        seed: seeds frame sampling, random initialisation and everything stochastic.
        backend: rasterizer backend (``"auto"``, ``"cpu"``, ``"gsplat"``, ``"reference"``).
        device: ``"auto"`` (CUDA when available), ``"cpu"`` or ``"cuda"``.
        eval_train_frames: training frames (evenly spaced) rendered at the end for ``psnr_train``.
        progress_every: steps between ``progress`` callbacks.
        eval_every: every this many steps the test frames are scored and logged (and reported to
            ``progress`` as ``psnr_test``); 0 = only at the end.
        num_threads: torch and numba threads (0 = leave the process's setting); process-wide, see
            ``simsplat_core.compute_threads``.
    """

    iterations: int = 900
    cameras_per_step: int = 3
    lr: LearningRates = field(default_factory=LearningRates)
    densify: DensifyConfig = field(default_factory=DensifyConfig)
    loss: LossWeights = field(default_factory=LossWeights)
    init: InitConfig = field(default_factory=InitConfig)
    deform_holdout: float = 0.5
    eps2d: float = 0.1
    refine_poses: bool = False
    seed: int = 0
    backend: str = "auto"
    device: str = "auto"
    eval_train_frames: int = 4
    progress_every: int = 10
    eval_every: int = 0
    num_threads: int = 0

    def __post_init__(self) -> None:
        p = "ReconstructionConfig"
        _check(isinstance(self.iterations, int) and self.iterations > 0, f"{p}.iterations", "must be a positive int",
               self.iterations)
        _check(isinstance(self.cameras_per_step, int) and self.cameras_per_step > 0, f"{p}.cameras_per_step",
               "must be a positive int", self.cameras_per_step)
        _check(self.backend in BACKENDS, f"{p}.backend", f"must be one of {BACKENDS}", self.backend)
        _check(self.device in DEVICES, f"{p}.device", f"must be one of {DEVICES}", self.device)
        _check(isinstance(self.eval_train_frames, int) and self.eval_train_frames >= 0, f"{p}.eval_train_frames",
               "must be an int >= 0", self.eval_train_frames)
        _check(isinstance(self.progress_every, int) and self.progress_every > 0, f"{p}.progress_every",
               "must be a positive int", self.progress_every)
        _check(isinstance(self.eval_every, int) and self.eval_every >= 0, f"{p}.eval_every", "must be an int >= 0",
               self.eval_every)
        _check(isinstance(self.num_threads, int) and self.num_threads >= 0, f"{p}.num_threads", "must be an int >= 0",
               self.num_threads)
        _check(0 <= self.deform_holdout <= 1, f"{p}.deform_holdout", "must be in [0, 1]", self.deform_holdout)
        _check(isinstance(self.eps2d, (int, float)) and 0 <= self.eps2d < 10, f"{p}.eps2d", "must be in [0, 10)",
               self.eps2d)
        self.lr.validate(f"{p}.lr")
        self.densify.validate(f"{p}.densify")
        self.loss.validate(f"{p}.loss")
        self.init.validate(f"{p}.init")
