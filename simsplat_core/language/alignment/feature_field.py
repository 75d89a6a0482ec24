"""Per-Gaussian appearance features ``c_app [N, d]`` fitted by rendering (SIMSplat Sec. 3.2, as LangSplat).

Every Gaussian carries a ``d``-dim latent of the scene's ``FeatureAutoencoder`` (``GaussianSet.features``,
so the graph carries it and ``SceneGraph.to_records`` writes it). Rendering the latents like colours
gives a feature image ``F = sum_i T_i alpha_i c_i + T_final z_bg`` per camera (the rasterizer's
``D``-channel path, background "colour" ``z_bg``); decoding ``F`` through the autoencoder gives a
text-space feature per pixel whose cosine with a query embedding is a relevance map.

**Targets.** At each training pixel the target is the latent of the node that owns the pixel in the
node-id map (``node_masks``): ``z_v = encode(f_app(v))`` for an object node ``v`` with an appearance
feature, ``z_bg`` for the background node and for pixels where nothing opaque was hit. Pixels of
object nodes without a feature (never seen large enough to caption) carry no target.

**Background latent.** ``z_bg = encode(embedding of a background passage)`` ("road, sidewalk,
buildings, trees and sky" by default, trained into the scene's autoencoder next to the objects'
features), not the zero latent: ``decode(0)`` is the autoencoder's training mean, the centroid of the
scene's object captions, so every object query would light up the background about as much as an
average object; the passage decodes to a feature that is *not* any object (default sequence: the
objects' caption queries have mean cosine 0.88 with ``decode(0)``, 0.78 with the decoded passage and
0.94 with their own object's ``f_app``). It is kept in the graph's
metadata (``BACKGROUND_LATENT_KEY``) so a stored graph renders relevance maps on its own.

**Fit.** Each Gaussian starts at its node's latent (background Gaussians at ``z_bg``), so interior
pixels are right from the start; optimisation fixes mixed pixels at silhouettes, where Gaussians of
several nodes blend. Geometry is frozen: only the features are optimised (squared error in latent
space, object pixels weighted ``object_weight`` times, one frame's cameras per step, Adam restricted
to the Gaussians visible in the step's view). On the CPU backend the projection and tile binning of
every training view are computed once and reused, so a step is one compositing pass forward and
backward. Measured on the default synthetic sequence (``bench/bench_alignment.py``, 40 steps on 10
views): object-pixel latent MSE 0.149 -> 0.055, decoded cosine to the owner's feature 0.994 -> 0.998,
nearest-target accuracy 0.968 -> 0.990. (An L1 loss, as in LangSplat, made it worse here: its
gradient does not vanish at the exact fit, so Adam keeps shaking the already-right background.)

    views = feature_views(log, maps, frames=range(0, 40, 4))
    report = fit_feature_field(graph, views, node_latents, z_bg, FeatureFitConfig(), autoencoder=ae,
                               node_targets=targets, background_target=f_bg)
    fitted = report.graph                                                            # graph is unchanged
    relevance = similarity_map(fitted, 12, c2w, Ks, 240, 160, ae, query)          # [C, H, W]
"""

from __future__ import annotations

import dataclasses
import json
import logging
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from simsplat_core.language.appearance.autoencoder import FeatureAutoencoder
from simsplat_core.language.node_masks import NO_NODE, NodeIdMaps
from simsplat_core.language.text import l2_normalise
from simsplat_core.render import rasterization, select_backend
from simsplat_core.render.cpu_backend import rasterize_to_pixels
from simsplat_core.render.types import BACKENDS
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.nodes import BACKGROUND_ID
from simsplat_core.scene.render import world_to_camera
from simsplat_core.types import CameraImage, SceneLog

logger = logging.getLogger(__name__)

#: ``SceneGraph.metadata`` key of the background latent (a JSON list of ``d`` floats).
BACKGROUND_LATENT_KEY = "language_background_latent"
#: Targets at least this similar are look-alikes for the fit's nearest-target accuracy (the convention of
#: ``bench/bench_appearance.py``).
LOOK_ALIKE_COSINE = 0.99


class FeatureFieldError(ValueError):
    """The graph has no (or inconsistent) per-Gaussian features; the message says what is missing."""


@dataclass(frozen=True)
class FeatureFitConfig:
    """Optimisation of the per-Gaussian features.

    Attributes:
        iterations: Adam steps (one training view, i.e. one frame's cameras, per step); 0 keeps the
            node-latent initialisation.
        lr: Adam learning rate (latent units; latents have norms of about 3-5).
        object_weight: loss weight of object pixels relative to background pixels (objects are a
            small share of the pixels and the reason for the field).
        backend: rasterizer backend (``BACKENDS``).
        eval_views: views (evenly spread over the training views) on which the fit is measured
            before and after.
        eval_pixel_stride: measure every ``eval_pixel_stride``-th pixel in x and y.
        seed: order of the training views.
    """

    iterations: int = 40
    lr: float = 0.05
    object_weight: float = 5.0
    backend: str = "auto"
    eval_views: int = 4
    eval_pixel_stride: int = 2
    seed: int = 0

    def validate(self, prefix: str = "FeatureFitConfig") -> FeatureFitConfig:
        """Raises ``ValueError`` naming the offending field."""
        if not isinstance(self.iterations, int) or self.iterations < 0:
            raise ValueError(f"{prefix}.iterations must be an int >= 0, got {self.iterations!r}")
        if not self.lr > 0:
            raise ValueError(f"{prefix}.lr must be > 0, got {self.lr!r}")
        if not self.object_weight > 0:
            raise ValueError(f"{prefix}.object_weight must be > 0, got {self.object_weight!r}")
        if self.backend not in BACKENDS:
            raise ValueError(f"{prefix}.backend must be one of {BACKENDS}, got {self.backend!r}")
        if not isinstance(self.eval_views, int) or self.eval_views < 0:
            raise ValueError(f"{prefix}.eval_views must be an int >= 0, got {self.eval_views!r}")
        if not isinstance(self.eval_pixel_stride, int) or self.eval_pixel_stride < 1:
            raise ValueError(f"{prefix}.eval_pixel_stride must be an int >= 1, got {self.eval_pixel_stride!r}")
        return self


@dataclass(frozen=True, eq=False)
class FeatureView:
    """The cameras of one frame (one image size) and their per-pixel node ids.

    Attributes:
        frame_idx: the frame.
        cameras: ``C`` camera names.
        cam_to_world: ``[C, 4, 4]`` float32 OpenCV camera->world.
        Ks: ``[C, 3, 3]`` float32 intrinsics.
        width, height: image size.
        node_ids: ``[C, H, W]`` int32 node ids (``-1``: nothing opaque hit).
    """

    frame_idx: int
    cameras: tuple[str, ...]
    cam_to_world: np.ndarray
    Ks: np.ndarray
    width: int
    height: int
    node_ids: np.ndarray


def feature_views(log: SceneLog, maps: NodeIdMaps, frames: Iterable[int] | None = None) -> list[FeatureView]:
    """One ``FeatureView`` per (frame, image size) of ``log``'s images at ``frames`` (default: all of
    ``maps``), with the rendered node-id maps as targets."""
    groups: dict[tuple[int, int, int], list[CameraImage]] = {}
    for img in maps.images_of(log.images, frames):
        groups.setdefault((int(img.frame_idx), img.width, img.height), []).append(img)
    out = []
    for (frame, width, height), images in sorted(groups.items()):
        out.append(FeatureView(
            frame_idx=frame, cameras=tuple(img.camera for img in images),
            cam_to_world=np.stack([img.cam_to_world for img in images]).astype(np.float32),
            Ks=np.stack([img.K for img in images]).astype(np.float32), width=width, height=height,
            node_ids=np.stack([maps.image(frame, img.camera) for img in images]).astype(np.int32),
        ))
    return out


# ---------------------------------------------------------------------------------------------- storage
def set_gaussian_features(graph: SceneGraph, features: Tensor | np.ndarray) -> SceneGraph:
    """A copy of ``graph`` whose nodes' ``GaussianSet.features`` are ``features [N, d]`` (rows in the graph's
    canonical order, ``SceneGraph.node_offsets``; detached copies on the graph's device). ``graph`` is not
    changed."""
    features = torch.as_tensor(np.asarray(features) if isinstance(features, np.ndarray) else features)
    n = graph.num_gaussians
    if features.dim() != 2 or features.shape[0] != n:
        raise FeatureFieldError(f"features must be [N={n}, d], got {list(features.shape)}")
    features = features.detach().to(device=graph.device, dtype=torch.float32)
    offsets = graph.node_offsets()
    nodes = []
    for node in graph.nodes:
        start, stop = offsets[node.node_id]
        gaussians = dataclasses.replace(node.gaussians, features=features[start:stop].clone())
        nodes.append(dataclasses.replace(node, gaussians=gaussians))
    return dataclasses.replace(graph, nodes=tuple(nodes))


def gaussian_features(graph: SceneGraph) -> Tensor:
    """``[N, d]`` per-Gaussian features in canonical order (a copy).

    Raises:
        FeatureFieldError: a node has no features, or widths differ.
    """
    parts, widths = [], set()
    for node in graph.nodes:
        feats = node.gaussians.features
        if feats is None:
            raise FeatureFieldError(f"node {node.node_id} has no per-Gaussian features (fit the feature field first)")
        widths.add(int(feats.shape[1]))
        parts.append(feats.detach())
    if len(widths) > 1:
        raise FeatureFieldError(f"nodes have features of different widths {sorted(widths)}")
    return torch.cat(parts)  # a new tensor


def store_background_latent(graph: SceneGraph, latent: np.ndarray) -> SceneGraph:
    """A copy of ``graph`` that keeps ``z_bg [d]`` in its metadata (written to records with the graph)."""
    return graph.with_metadata(**{BACKGROUND_LATENT_KEY: json.dumps([float(v) for v in
                                                                     np.asarray(latent, dtype=np.float64)])})


def background_latent(graph: SceneGraph) -> np.ndarray | None:
    """``[d]`` float32 background latent stored in the graph's metadata, or ``None``."""
    text = graph.metadata.get(BACKGROUND_LATENT_KEY)
    return None if text is None else np.asarray(json.loads(text), dtype=np.float32)


def initial_features(graph: SceneGraph, node_latents: Mapping[int, np.ndarray], background: np.ndarray) -> Tensor:
    """``[N, d]``: every Gaussian at its node's latent; the background node and object nodes without a
    latent at ``background``."""
    background = np.asarray(background, dtype=np.float32).reshape(-1)
    rows = []
    for node in graph.nodes:
        z = node_latents.get(node.node_id) if node.node_id != BACKGROUND_ID else None
        z = background if z is None else np.asarray(z, dtype=np.float32).reshape(-1)
        if z.shape != background.shape:
            raise FeatureFieldError(f"node {node.node_id}: latent of width {z.shape[0]}, "
                                    f"background {background.shape[0]}")
        rows.append(np.broadcast_to(z, (len(node.gaussians), z.shape[0])))
    return torch.as_tensor(np.concatenate(rows), device=graph.device)


def node_mean_features(graph: SceneGraph, node_ids: Iterable[int] | None = None) -> dict[int, np.ndarray]:
    """``node_id -> [d]`` opacity-weighted mean of the node's per-Gaussian features."""
    wanted = None if node_ids is None else set(int(n) for n in node_ids)
    out = {}
    for node in graph.nodes:
        if wanted is not None and node.node_id not in wanted:
            continue
        feats = node.gaussians.features
        if feats is None:
            raise FeatureFieldError(f"node {node.node_id} has no per-Gaussian features")
        if len(node.gaussians) == 0:
            continue
        w = node.gaussians.opacities.detach()
        out[node.node_id] = ((w[:, None] * feats.detach()).sum(0) / w.sum().clamp_min(1e-12)).cpu().numpy()
    return out


# ---------------------------------------------------------------------------------------------- rendering
class _ViewRenderer:
    """Renders per-Gaussian features into one view with the geometry frozen.

    On the CPU backend the projection and tile binning are done once here; every ``render`` is a
    single differentiable compositing pass. Other backends rasterize the cached composed Gaussians.
    """

    def __init__(self, graph: SceneGraph, frame: float, cam_to_world: np.ndarray | Tensor, Ks: np.ndarray | Tensor,
                 width: int, height: int, backend: str) -> None:
        device = graph.device
        self.width, self.height = int(width), int(height)
        self.eps2d = graph.eps2d
        with torch.no_grad():
            composed = graph.at(frame).detach()
            self.gaussian_ids = composed.gaussian_ids
            c2w = torch.as_tensor(cam_to_world, dtype=torch.float32, device=device)
            self.Ks = torch.as_tensor(Ks, dtype=torch.float32, device=device)
            self.viewmats = world_to_camera(c2w)
            self.n_cams = int(c2w.shape[0])
            self.backend = select_backend(backend, device)
            ones = composed.opacities.new_ones((len(composed), 1))
            _, _, meta = rasterization(composed.means, composed.quats, composed.scales, composed.opacities, ones,
                                       self.viewmats, self.Ks, self.width, self.height, render_mode="RGB",
                                       backend=self.backend, eps2d=self.eps2d)
            radii = meta.radii
            if self.backend == "cpu":  # keep the projection and tile binning; each render only composites
                self.means2d, self.conics = meta.means2d.detach(), meta.conics.detach()
                self.opacities = meta.opacities.detach()
                if meta.isect_offsets is None or meta.flatten_ids is None:
                    raise FeatureFieldError(f"backend {self.backend!r} returned no tile binning to reuse")
                self.tile_size = meta.tile_size
                self.isect_offsets, self.flatten_ids = meta.isect_offsets, meta.flatten_ids
                self.composed = None
            else:
                self.composed = composed
            #: ``[N_graph]`` bool, canonical rows of the Gaussians visible in some camera of the view
            self.visible = torch.zeros(graph.num_gaussians, dtype=torch.bool, device=device)
            self.visible[self.gaussian_ids[(radii.reshape(self.n_cams, len(composed), -1) > 0).any(-1).any(0)]] = True

    def render(self, features: Tensor, background: Tensor) -> Tensor:
        """``[C, H, W, d]`` composited features (``features [N, d]`` in canonical order, ``background [d]``)."""
        colors = features[self.gaussian_ids]
        bgs = background.reshape(1, -1).expand(self.n_cams, -1)
        if self.composed is None:
            colors = colors[None].expand(self.n_cams, -1, -1)
            out, _ = rasterize_to_pixels(self.means2d, self.conics, colors, self.opacities, self.width, self.height,
                                         self.tile_size, self.isect_offsets, self.flatten_ids, bgs)
            return out
        c = self.composed
        out, _, _ = rasterization(c.means, c.quats, c.scales, c.opacities, colors, self.viewmats, self.Ks, self.width,
                                  self.height, render_mode="RGB", backgrounds=bgs, backend=self.backend,
                                  eps2d=self.eps2d)
        return out


def render_features(
    graph: SceneGraph,
    t: float,
    cam_to_world: np.ndarray | Tensor,  # [C, 4, 4]
    Ks: np.ndarray | Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    *,
    background: np.ndarray | None = None,
    backend: str = "auto",
) -> Tensor:
    """``[C, H, W, d]`` rendered per-Gaussian features at ``t`` (no grad); ``background`` defaults to the
    graph's stored background latent (zeros when there is none)."""
    feats = gaussian_features(graph)
    if background is None:
        background = background_latent(graph)
    bg = torch.zeros(feats.shape[1]) if background is None else torch.as_tensor(background, dtype=torch.float32)
    if bg.shape != (feats.shape[1],):
        raise FeatureFieldError(f"background latent has shape {list(bg.shape)}, features are {feats.shape[1]}-d")
    device = graph.device
    with torch.no_grad():
        c = graph.at(t).detach()
        c2w = torch.as_tensor(cam_to_world, dtype=torch.float32, device=device)
        out, _, _ = rasterization(c.means, c.quats, c.scales, c.opacities, feats[c.gaussian_ids], world_to_camera(c2w),
                                  torch.as_tensor(Ks, dtype=torch.float32, device=device), width, height,
                                  render_mode="RGB",
                                  backgrounds=bg.to(feats.device).reshape(1, -1).expand(c2w.shape[0], -1),
                                  backend=backend, eps2d=graph.eps2d)
    return out


def _decode_pixels(autoencoder: FeatureAutoencoder, latents: Tensor, chunk: int = 65536) -> Tensor:
    """``[P, d]`` -> ``[P, D]`` unit features on the CPU, in chunks."""
    latents = latents.detach().to("cpu", torch.float32)
    with torch.no_grad():
        return torch.cat([autoencoder.decode_torch(latents[i:i + chunk]) for i in range(0, latents.shape[0], chunk)]) \
            if latents.shape[0] else torch.zeros((0, autoencoder.input_dim))


def similarity_map(
    graph: SceneGraph,
    t: float,
    cam_to_world: np.ndarray | Tensor,  # [C, 4, 4]
    Ks: np.ndarray | Tensor,  # [C, 3, 3]
    width: int,
    height: int,
    autoencoder: FeatureAutoencoder,
    query_embedding: np.ndarray,
    *,
    background: np.ndarray | None = None,
    backend: str = "auto",
) -> np.ndarray:
    """Relevance of every pixel to a query: cosine between the pixel's decoded rendered feature and
    the query embedding (``encode_queries`` in the autoencoder's text space).

    Args:
        query_embedding: ``[D]`` one query, or ``[Q, D]`` several (rendered and decoded once).
        background: latent behind the scene (default: the graph's stored background latent).

    Returns:
        ``[C, H, W]`` float32 for one query, ``[Q, C, H, W]`` for several.
    """
    queries = np.asarray(query_embedding, dtype=np.float32)
    single = queries.ndim == 1
    queries = queries.reshape(1, -1) if single else queries
    if queries.ndim != 2 or queries.shape[1] != autoencoder.input_dim:
        raise ValueError(f"query has {queries.shape[-1]} dims, the autoencoder decodes to {autoencoder.input_dim}")
    queries = l2_normalise(queries)
    rendered = render_features(graph, t, cam_to_world, Ks, width, height, background=background, backend=backend)
    c, h, w, d = rendered.shape
    decoded = _decode_pixels(autoencoder, rendered.reshape(-1, d))  # [P, D]
    sims = (decoded @ torch.from_numpy(queries).T).T.reshape(-1, c, h, w).numpy().astype(np.float32)
    return sims[0] if single else sims


# ---------------------------------------------------------------------------------------------- fitting
@dataclass(frozen=True)
class FieldFitReport:
    """How well the rendered features match the per-pixel targets, before and after the fit.

    ``latent_mse`` is the squared latent error (summed over channels) over all target pixels of the
    evaluation views, ``object_latent_mse`` over their object pixels; the decoded figures (``nan``
    without an autoencoder and text-space targets) compare ``decode(rendered)`` with the owning node's
    text-space feature ``f`` (``background_target`` for background pixels):

    * ``cosine``: mean over target pixels of ``cos(decode(F), f)``;
    * ``object_cosine``: the same over object pixels only;
    * ``object_accuracy``: share of object pixels whose decoded feature is closest to their own node's
      ``f`` among all targets, or to a look-alike's (targets with cosine >= ``LOOK_ALIKE_COSINE``:
      two red sedans whose per-view captions mix slightly differently).
    ``graph`` is a copy of the input graph holding the fitted features (the input is not changed).
    """

    graph: SceneGraph = dataclasses.field(repr=False, compare=False)
    iterations: int
    seconds: float
    views: int
    eval_views: int
    loss_first: float
    loss_last: float
    latent_mse_before: float
    latent_mse_after: float
    object_latent_mse_before: float
    object_latent_mse_after: float
    cosine_before: float
    cosine_after: float
    object_cosine_before: float
    object_cosine_after: float
    object_accuracy_before: float
    object_accuracy_after: float
    node_features: dict[int, np.ndarray] = dataclasses.field(default_factory=dict, repr=False)

    def summary(self, prefix: str = "fit_") -> dict[str, float]:
        """Flat numbers for reports (``node_features`` and ``graph`` left out)."""
        return {prefix + f.name: float(getattr(self, f.name)) for f in dataclasses.fields(self)
                if f.name not in ("node_features", "graph")}


class _VisibleAdam:
    """Adam that updates only the rows visible in the current view (gsplat's ``SelectiveAdam``).

    A view's loss gives no gradient to Gaussians outside it; plain Adam would keep moving them on stale
    momentum (measured: the background's latents drifted and the latent error over all pixels rose
    while the training loss fell). Here moments, bias corrections (per-row step counts) and values
    change on the visible rows only (dense masked updates: cheaper than gathering the rows).
    """

    def __init__(self, param: Tensor, lr: float, betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8) -> None:
        self.param, self.lr, self.betas, self.eps = param, lr, betas, eps
        self.m = torch.zeros_like(param)
        self.v = torch.zeros_like(param)
        self.steps = torch.zeros((param.shape[0], 1), dtype=param.dtype, device=param.device)

    @torch.no_grad()
    def step(self, visible: Tensor) -> None:
        """One update of the rows where ``visible [N]`` (bool) is true; clears the gradient."""
        grad = self.param.grad
        if grad is None:
            return
        b1, b2 = self.betas
        mask = visible[:, None]
        self.steps += mask.to(self.steps.dtype)
        self.m.copy_(torch.where(mask, self.m * b1 + grad * (1 - b1), self.m))
        self.v.copy_(torch.where(mask, self.v * b2 + grad * grad * (1 - b2), self.v))
        t = self.steps.clamp_min(1)
        update = (self.m / (1 - b1 ** t)) / ((self.v / (1 - b2 ** t)).sqrt() + self.eps)
        self.param.sub_(torch.where(mask, self.lr * update, torch.zeros_like(update)))
        self.param.grad = None


def _rows_by_node(size: int, values: Mapping[int, np.ndarray], background: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """``([size, D] float32, [size] bool)``: row ``node_id + 1`` holds ``values[node_id]`` (object nodes),
    rows 0 (no node hit, id -1) and ``BACKGROUND_ID + 1`` hold ``background``; the mask says which rows
    are set."""
    bg = np.asarray(background, dtype=np.float32).reshape(-1)
    rows = np.zeros((size, bg.shape[0]), dtype=np.float32)
    valid = np.zeros(size, dtype=bool)
    for node_id, value in values.items():
        if 0 <= node_id < size - 1 and node_id != BACKGROUND_ID:
            rows[node_id + 1], valid[node_id + 1] = np.asarray(value, dtype=np.float32).reshape(-1), True
    for row in (0, BACKGROUND_ID + 1):
        rows[row], valid[row] = bg, True
    return rows, valid


class _Targets:
    """Per-node target latents and text-space features as lookup tables indexed by ``node_id + 1``
    (row 0 is ``-1``, nothing hit: the background)."""

    def __init__(self, graph: SceneGraph, node_latents: Mapping[int, np.ndarray], background: np.ndarray,
                 node_targets: Mapping[int, np.ndarray] | None, background_target: np.ndarray | None,
                 device: torch.device) -> None:
        size = max(n.node_id for n in graph.nodes) + 2
        latent, valid = _rows_by_node(size, node_latents, background)
        self.latent = torch.from_numpy(latent).to(device)
        self.valid = torch.from_numpy(valid).to(device)
        self.text: Tensor | None = None
        if node_targets is not None and background_target is not None:
            text, has = _rows_by_node(size, node_targets, background_target)
            text = l2_normalise(text)
            self.text_valid = torch.from_numpy(has)
            # candidate targets of the nearest-target accuracy; targets within LOOK_ALIKE_COSINE of each
            # other are look-alikes (two red sedans) and count as the same answer
            rows = np.flatnonzero(valid & has)
            self.text = torch.from_numpy(text)
            self.candidates = torch.from_numpy(text[rows])  # [K, D]
            self.candidate_of = torch.full((size,), -1, dtype=torch.long)
            self.candidate_of[torch.from_numpy(rows)] = torch.arange(rows.shape[0])
            self.look_alike = (self.candidates @ self.candidates.T) >= LOOK_ALIKE_COSINE  # [K, K]

    def index(self, node_ids: np.ndarray, device: torch.device) -> Tensor:
        return torch.as_tensor(np.maximum(node_ids.astype(np.int64), NO_NODE) + 1, device=device)


def _evaluate(renderers: Sequence[_ViewRenderer], views: Sequence[FeatureView], features: Tensor, bg: Tensor,
              targets: _Targets, autoencoder: FeatureAutoencoder | None, stride: int) -> dict[str, float]:
    sums = {"sq": 0.0, "px": 0, "obj_sq": 0.0, "obj_sq_px": 0, "cos": 0.0, "text_px": 0, "obj_cos": 0.0,
            "obj_px": 0, "obj_right": 0.0}
    with torch.no_grad():
        for renderer, view in zip(renderers, views):
            out = renderer.render(features, bg)[:, ::stride, ::stride]  # [C, h, w, d]
            idx = targets.index(view.node_ids[:, ::stride, ::stride], out.device)
            keep = targets.valid[idx]
            pred, row = out[keep], idx[keep]
            sq = (pred - targets.latent[row]).square().sum(-1)
            on_object = row > BACKGROUND_ID + 1
            sums["sq"] += float(sq.sum())
            sums["px"] += int(row.shape[0])
            sums["obj_sq"] += float(sq[on_object].sum())
            sums["obj_sq_px"] += int(on_object.sum())
            if autoencoder is None or targets.text is None:  # nothing decoded to compare with the text targets
                continue
            row = row.cpu()
            has = targets.text_valid[row]
            pred, row = pred.cpu()[has], row[has]
            dec = _decode_pixels(autoencoder, pred)
            cos = (dec * targets.text[row]).sum(-1)
            obj = row > BACKGROUND_ID + 1
            nearest = (dec[obj] @ targets.candidates.T).argmax(-1)
            sums["cos"] += float(cos.sum())
            sums["text_px"] += int(row.shape[0])
            sums["obj_cos"] += float(cos[obj].sum())
            sums["obj_px"] += int(obj.sum())
            sums["obj_right"] += float(targets.look_alike[targets.candidate_of[row[obj]], nearest].sum())
    ratio = lambda a, b: sums[a] / sums[b] if sums[b] else float("nan")  # noqa: E731
    return {"latent_mse": ratio("sq", "px"), "object_latent_mse": ratio("obj_sq", "obj_sq_px"),
            "cosine": ratio("cos", "text_px"), "object_cosine": ratio("obj_cos", "obj_px"),
            "object_accuracy": ratio("obj_right", "obj_px")}


def _rendered_node_means(renderers: Sequence[_ViewRenderer], views: Sequence[FeatureView], features: Tensor,
                         bg: Tensor, node_ids: Iterable[int]) -> dict[int, np.ndarray]:
    """``node_id -> [d]`` mean rendered latent over the node's own pixels in ``views`` (nodes never seen
    are left out)."""
    wanted = sorted(int(n) for n in node_ids)
    if not wanted or not views:
        return {}
    size = max(wanted) + 1
    sums = torch.zeros((size, features.shape[1]), dtype=torch.float64)
    counts = torch.zeros(size, dtype=torch.float64)
    lookup = np.full(size + 1, -1, dtype=np.int64)
    lookup[wanted] = wanted
    with torch.no_grad():
        for renderer, view in zip(renderers, views):
            ids = np.where((view.node_ids >= 0) & (view.node_ids < size), view.node_ids, size)
            rows = torch.from_numpy(lookup[ids])
            keep = rows >= 0
            if not bool(keep.any()):
                continue
            out = renderer.render(features, bg).cpu().to(torch.float64)
            sums.index_add_(0, rows[keep], out[keep])
            counts.index_add_(0, rows[keep], torch.ones(int(keep.sum()), dtype=torch.float64))
    return {n: (sums[n] / counts[n]).numpy().astype(np.float32) for n in wanted if counts[n] > 0}


def fit_feature_field(
    graph: SceneGraph,
    views: Sequence[FeatureView],
    node_latents: Mapping[int, np.ndarray],
    background: np.ndarray,
    config: FeatureFitConfig = FeatureFitConfig(),
    *,
    autoencoder: FeatureAutoencoder | None = None,
    node_targets: Mapping[int, np.ndarray] | None = None,
    background_target: np.ndarray | None = None,
) -> FieldFitReport:
    """Initialise every Gaussian's feature at its node's latent and optimise the features only.

    Args:
        graph: the scene; it is not changed (the fitted graph is ``report.graph``).
        views: training views with node-id targets (``feature_views``).
        node_latents: ``node_id -> [d]`` target latent of each object node with an appearance feature.
        background: ``[d]`` latent of the background and of pixels where nothing was hit.
        config: optimisation.
        autoencoder, node_targets, background_target: for the decoded figures of the report only
            (``node_id -> [D]`` text-space features, ``[D]`` background feature).

    Returns:
        the fit report (latent MSE, decoded cosine and nearest-target accuracy before/after) with the
        mean rendered latent over each node's own pixels in ``views`` (``node_features``) and the fitted
        graph (``graph``: a copy of ``graph`` whose nodes carry the fitted ``[n, d]`` features and whose
        metadata keeps ``background``).
    """
    config.validate()
    t0 = time.perf_counter()
    device = graph.device
    background = np.asarray(background, dtype=np.float32).reshape(-1)
    features = initial_features(graph, node_latents, background)
    bg = torch.as_tensor(background, device=device)
    targets = _Targets(graph, node_latents, background, node_targets, background_target, device)
    renderers = [_ViewRenderer(graph, v.frame_idx, v.cam_to_world, v.Ks, v.width, v.height, config.backend)
                 for v in views]
    n_eval = min(config.eval_views, len(views))
    eval_pick = sorted({int(round(i)) for i in np.linspace(0, len(views) - 1, n_eval)}) if n_eval else []
    eval_r = [renderers[i] for i in eval_pick]
    eval_v = [views[i] for i in eval_pick]
    before = _evaluate(eval_r, eval_v, features, bg, targets, autoencoder, config.eval_pixel_stride)

    target_idx = [targets.index(v.node_ids, device) for v in views]
    param = features.clone().requires_grad_(True)
    optim = _VisibleAdam(param, config.lr)
    order = np.random.default_rng(config.seed).permutation(len(views)) if views else np.zeros(0, np.int64)
    losses: list[float] = []
    for step in range(config.iterations if views else 0):
        k = int(order[step % len(views)])
        idx = target_idx[k]
        keep = targets.valid[idx]
        out = renderers[k].render(param, bg)
        err = (out - targets.latent[idx]).square().sum(-1)  # [C, H, W]
        weight = keep.to(err.dtype) * torch.where(idx > BACKGROUND_ID + 1, float(config.object_weight), 1.0)
        loss = (err * weight).sum() / weight.sum().clamp_min(1e-12)
        loss.backward()
        optim.step(renderers[k].visible)
        losses.append(float(loss.detach()))
    fitted = param.detach()
    node_features = _rendered_node_means(renderers, views, fitted, bg, node_latents)
    after = _evaluate(eval_r, eval_v, fitted, bg, targets, autoencoder, config.eval_pixel_stride)
    seconds = time.perf_counter() - t0
    nan = float("nan")
    report = FieldFitReport(
        graph=store_background_latent(set_gaussian_features(graph, fitted), background),
        iterations=len(losses), seconds=seconds, views=len(views), eval_views=len(eval_v),
        loss_first=losses[0] if losses else nan, loss_last=losses[-1] if losses else nan,
        latent_mse_before=before["latent_mse"], latent_mse_after=after["latent_mse"],
        object_latent_mse_before=before["object_latent_mse"], object_latent_mse_after=after["object_latent_mse"],
        cosine_before=before["cosine"], cosine_after=after["cosine"],
        object_cosine_before=before["object_cosine"], object_cosine_after=after["object_cosine"],
        object_accuracy_before=before["object_accuracy"], object_accuracy_after=after["object_accuracy"],
        node_features=node_features,
    )
    logger.info("feature field: %d steps on %d views in %.1f s; latent MSE %.4f -> %.4f, object cosine %.4f -> %.4f",
                report.iterations, report.views, seconds, report.latent_mse_before, report.latent_mse_after,
                report.object_cosine_before, report.object_cosine_after)
    return report


__all__ = [
    "BACKGROUND_LATENT_KEY",
    "FeatureFieldError",
    "FeatureFitConfig",
    "FeatureView",
    "FieldFitReport",
    "background_latent",
    "feature_views",
    "fit_feature_field",
    "gaussian_features",
    "initial_features",
    "node_mean_features",
    "render_features",
    "set_gaussian_features",
    "similarity_map",
    "store_background_latent",
]
