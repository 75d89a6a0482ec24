"""Build a ``LanguageScene`` from a reconstructed scene graph and its log (SIMSplat Sec. 3.2).

Stages (``BuiltLanguageScene.metrics`` times each, ``time_<stage>_s``):

1. ``node_maps``: node-id maps ``[F, C, H, W]`` of every frame and camera rendered from the graph
   (``node_masks.render_node_id_maps``); grounding cuts its per-frame masks from them.
2. ``crops``: the log's pixels under each object node's projected mask, every ``crop_frame_stride``-th
   frame (``node_masks.crops_from_node_maps``).
3. ``captions``: per object one caption (``captioner.describe_track`` over its views) and a
   text-space appearance feature (the embedder's view embeddings, averaged and renormalised).
4. ``autoencoder``: the scene's ``FeatureAutoencoder`` ``D -> d`` (fitted on the objects' features,
   the background passage and, optionally, the caption vocabulary, as LangSplat fits one per scene),
   unless one is passed in.
5. ``feature_field``: per-Gaussian latents initialised from their node's latent and fitted by
   rendering against the node-id maps of every ``fit_frame_stride``-th frame
   (``feature_field.fit_feature_field``); stored in the graph's ``GaussianSet.features``.
6. ``motion``: ``aligner.features(log)`` (vehicles, cyclists and pedestrians; ``None`` for static
   objects and signs, and for every object when no aligner is given).

``NodeLanguage.f_app`` is the decoded mean of the *fitted* feature field as rendered on the node's own
pixels in the fit views (unit norm; for a node those views miss, the opacity-weighted mean of its
Gaussians' latents), so it comes from the field that renders the relevance maps. The plain mean over
a node's Gaussians is not used where pixels exist: Gaussians straddling the silhouette are pulled
toward the background's latent by the fit and blur it (measured on the tiny test scene: cosine to the
target 0.95 for the Gaussians' mean against 0.99 for the rendered mean). Logs without pixels
(AV2: camera poses only) skip stages 1-5: ``f_app``, ``caption`` and ``node_id_maps`` are ``None`` and
motion still works; the graph may then be ``None`` (object nodes numbered like
``scene.init.initial_graph``: ``1..K`` in object-id order).

    built = build_language_scene(graph, log, text_encoder=encoder, aligner=aligner)
    built.scene                     # LanguageScene for the QueryEngine
    built.gaussian_features         # [N, d] in graph order (also in built.graph's GaussianSet.features)
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.language.alignment.feature_field import (
    FeatureFitConfig,
    feature_views,
    fit_feature_field,
    gaussian_features,
    node_mean_features,
)
from simsplat_core.language.alignment.motion_training import MotionAligner
from simsplat_core.language.appearance.autoencoder import AutoencoderConfig, FeatureAutoencoder
from simsplat_core.language.appearance.captioner import AppearanceCaption, appearance_vocabulary
from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.language.appearance.embedders import (
    CAPTIONERS,
    AppearanceEmbedder,
    CaptionEmbedder,
    aggregate_views,
    appearance_embedder,
)
from simsplat_core.language.node_masks import (
    NodeIdMaps,
    NodeObject,
    crops_from_node_maps,
    mask_agreement,
    node_objects,
    render_node_id_maps,
)
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage, ObjectMotionFeatures
from simsplat_core.language.text import TextEncoder, l2_normalise
from simsplat_core.render.types import BACKENDS
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.stage_clock import StageClock
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: The passage whose embedding is the background's appearance feature (see ``feature_field``).
BACKGROUND_PASSAGE = "road, sidewalk, buildings, trees and sky"


class AlignmentConfigError(ValueError):
    """An invalid ``AlignmentConfig`` value; the message names the field."""


@dataclass(frozen=True)
class AlignmentConfig:
    """How a ``LanguageScene`` is built.

    Attributes:
        feature_dim: ``d``, width of the per-Gaussian latents (the autoencoder's latent width).
        fit_iterations: Adam steps of the feature field (0: keep the node-latent initialisation).
        fit_lr: their learning rate.
        fit_object_weight: loss weight of object pixels relative to background pixels.
        fit_frame_stride: fit on every ``fit_frame_stride``-th frame with images.
        crop_frame_stride: caption every ``crop_frame_stride``-th frame's crops.
        min_area: a projected mask needs this many pixels to become a crop (``crops_from_log`` semantics).
        small_area: an object none of whose masks reaches ``min_area`` is described from its masks of
            at least this many pixels instead (0, or >= ``min_area``: such objects get no appearance). Far objects are
            often never 100 px large; the built-in captioner keeps 95-99 % of its per-view colour
            accuracy at 30 px (``bench/results/appearance.json``) and the vote over views helps.
        crop_margin: pixels of context around each crop's mask.
        captioner: ``"builtin"`` (rule-based, offline) or ``"vlm"`` (a VLM over the OpenAI-compatible API,
            endpoint from ``SIMSPLAT_VLM_URL`` / ``SIMSPLAT_VLM_MODEL``); see ``appearance_embedder``.
        autoencoder_steps: Adam steps of the scene autoencoder (when none is passed in).
        use_vocabulary: train the autoencoder on the caption vocabulary too (~240 phrases: latents
            between and around the scene's looks decode to sensible text). Off by default: what is decoded
            here (relevance maps, ``f_app``) lies at or between the scene's own latents, which an
            autoencoder of the scene's features alone reproduces better (``bench/bench_alignment.py``,
            seed 0: object-pixel nearest-target accuracy 0.99 vs 0.97, ``f_app`` vs caption cosine
            0.997 vs 0.993) and 4x faster; the vocabulary also costs ~240 E5 passages per process.
        background_passage: text whose embedding stands for the background (``None``: the zero latent).
        eval_views: views on which the fit is measured before/after (0 skips the measurement).
        measure_masks: compare projected masks with ground-truth instance masks when the log has them.
        backend: rasterizer backend.
        seed: seeds the autoencoder and the fit's view order.
    """

    feature_dim: int = 8
    fit_iterations: int = 40
    fit_lr: float = 0.05
    fit_object_weight: float = 5.0
    fit_frame_stride: int = 4
    crop_frame_stride: int = 1
    min_area: int = 100
    small_area: int = 30
    crop_margin: int = 2
    captioner: str = "builtin"
    autoencoder_steps: int = 500
    use_vocabulary: bool = False
    background_passage: str | None = BACKGROUND_PASSAGE
    eval_views: int = 4
    measure_masks: bool = True
    backend: str = "auto"
    seed: int = 0

    def validate(self) -> AlignmentConfig:
        """Raises ``AlignmentConfigError`` naming the offending field; returns ``self``."""
        def need(cond: bool, name: str, rule: str) -> None:
            if not cond:
                raise AlignmentConfigError(f"AlignmentConfig.{name} {rule}, got {getattr(self, name)!r}")

        def is_int(name: str) -> bool:
            value = getattr(self, name)
            return isinstance(value, int) and not isinstance(value, bool)

        need(self.captioner in CAPTIONERS, "captioner", f"must be one of {', '.join(CAPTIONERS)}")
        for name in ("feature_dim", "fit_frame_stride", "crop_frame_stride", "autoencoder_steps"):
            need(is_int(name) and getattr(self, name) >= 1, name, "must be an int >= 1")
        for name in ("fit_iterations", "min_area", "small_area", "crop_margin", "eval_views", "seed"):
            need(is_int(name) and getattr(self, name) >= 0, name, "must be an int >= 0")
        for name in ("fit_lr", "fit_object_weight"):
            value = getattr(self, name)
            need(isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value) and value > 0,
                 name, "must be a finite number > 0")
        need(isinstance(self.use_vocabulary, bool), "use_vocabulary", "must be a bool")
        need(isinstance(self.measure_masks, bool), "measure_masks", "must be a bool")
        need(self.background_passage is None or (isinstance(self.background_passage, str)
                                                 and self.background_passage.strip() != ""),
             "background_passage", "must be None or a non-empty string")
        need(self.backend in BACKENDS, "backend", f"must be one of {BACKENDS}")
        return self

    @property
    def min_floor(self) -> int:
        """Smallest mask that may become a crop: ``min(small_area, min_area)`` (``min_area`` when
        ``small_area`` is 0)."""
        return min(self.small_area, self.min_area) if self.small_area > 0 else self.min_area

    def fit_config(self) -> FeatureFitConfig:
        return FeatureFitConfig(iterations=self.fit_iterations, lr=self.fit_lr, object_weight=self.fit_object_weight,
                                backend=self.backend, eval_views=self.eval_views, seed=self.seed)

    def autoencoder_config(self) -> AutoencoderConfig:
        return AutoencoderConfig(latent_dim=self.feature_dim, steps=self.autoencoder_steps, seed=self.seed)


@dataclass(frozen=True, eq=False)
class BuiltLanguageScene:
    """What ``build_language_scene`` returns.

    Attributes:
        scene: the ``LanguageScene``.
        gaussian_features: ``[N, d]`` float32 fitted per-Gaussian latents in the graph's canonical order
            (``SceneGraph.node_offsets``); ``None`` for logs without pixels.
        autoencoder: the scene's autoencoder (fitted or passed in); ``None`` when there were no pixels and
            none was passed.
        captions: ``object_id -> caption`` of every object with crops.
        graph: the scene graph with the fitted per-Gaussian features and background latent (a copy: the
            graph passed in is not changed); the input graph (or ``None``) when there were no pixels.
        metrics: stage times (``time_<stage>_s``, ``time_total_s``), counts, the fit report
            (``fit_*``) and, for logs with instance masks, the projected-mask agreement (``mask_*``).
    """

    scene: LanguageScene
    gaussian_features: np.ndarray | None
    autoencoder: FeatureAutoencoder | None
    captions: dict[str, AppearanceCaption]
    metrics: dict[str, float] = field(default_factory=dict)
    graph: SceneGraph | None = None


def _object_nodes(graph: SceneGraph | None, log: SceneLog) -> list[NodeObject]:
    if graph is not None:
        return list(node_objects(graph).values())
    objects = sorted(log.objects, key=lambda o: o.object_id)
    return [NodeObject(i, o.object_id, o.category) for i, o in enumerate(objects, start=1)]


def _has_pixels(log: SceneLog) -> bool:
    return any(img.image is not None for img in log.images)


def _check_autoencoder(autoencoder: FeatureAutoencoder | None, config: AlignmentConfig,
                       text_encoder: TextEncoder) -> None:
    """Raise ``ValueError`` unless a passed-in autoencoder maps the text space to ``config.feature_dim``."""
    if autoencoder is None:
        return
    if autoencoder.latent_dim != config.feature_dim:
        raise ValueError(f"autoencoder latent width {autoencoder.latent_dim} != AlignmentConfig.feature_dim "
                         f"{config.feature_dim}")
    if autoencoder.input_dim != text_encoder.dim:
        raise ValueError(f"autoencoder input width {autoencoder.input_dim} != text encoder {text_encoder.name} "
                         f"width {text_encoder.dim}")


@dataclass(frozen=True)
class _ObjectLooks:
    """Step 3's result: what each object looks like, in words and in the text space.

    Attributes:
        captions: ``object_id -> caption`` of every object with crops.
        features: ``object_id -> [D]`` text-space appearance feature (its views' embeddings, averaged).
        background: ``[D]`` embedding of ``AlignmentConfig.background_passage`` (``None`` without one).
    """

    captions: dict[str, AppearanceCaption]
    features: dict[str, np.ndarray]
    background: np.ndarray | None


@dataclass(frozen=True, eq=False)
class _FittedField:
    """Step 5's result.

    Attributes:
        graph: copy of the scene graph holding the fitted per-Gaussian latents and the background latent.
        f_app: ``node_id -> [D]`` unit appearance feature decoded from the field (module docstring).
        gaussian_features: ``[N, d]`` float32 fitted latents in the graph's canonical order.
        metrics: the fit report (``fit_*``) and ``f_app_vs_caption_cosine``.
    """

    graph: SceneGraph
    f_app: dict[int, np.ndarray]
    gaussian_features: np.ndarray
    metrics: dict[str, float]


def _projected_mask_agreement(log: SceneLog, maps: NodeIdMaps, graph: SceneGraph,
                              config: AlignmentConfig) -> dict[str, float]:
    """``mask_*`` agreement of the node-id maps with the log's instance masks (empty without them, or when
    ``config.measure_masks`` is off)."""
    if config.measure_masks and any(img.instance is not None for img in log.images):
        return mask_agreement(log, maps, graph, min_gt_pixels=config.min_area).summary()
    return {}


def _select_crops(crops: Sequence[ObjectCrop], config: AlignmentConfig) -> list[ObjectCrop]:
    """Per object its crops of at least ``min_area`` pixels, or, when it has none, all its crops (each of
    at least ``small_area``)."""
    large = {c.object_id for c in crops if c.area >= config.min_area}
    return [c for c in crops if c.area >= config.min_area or c.object_id not in large]


def _crops_under_node_maps(log: SceneLog, maps: NodeIdMaps, graph: SceneGraph,
                           config: AlignmentConfig) -> list[ObjectCrop]:
    """Step 2: the log's pixels under each object node's projected mask, every ``crop_frame_stride``-th frame,
    selected by ``_select_crops``."""
    frames = maps.frame_indices[::config.crop_frame_stride]
    return _select_crops(crops_from_node_maps(log, maps, graph, frames=frames, min_area=config.min_floor,
                                              margin=config.crop_margin), config)


def _crop_counts(crops: Sequence[ObjectCrop], config: AlignmentConfig) -> dict[str, float]:
    """How many crops there are, and how many objects are described from small crops only."""
    return {"objects_from_small_crops": float(len({c.object_id for c in crops if c.area < config.min_area})),
            "crops": float(len(crops))}


def _describe_objects(crops: Sequence[ObjectCrop], embedder: AppearanceEmbedder, text_encoder: TextEncoder,
                      config: AlignmentConfig) -> _ObjectLooks:
    """Step 3: one caption per object (an image-feature embedder still gets the built-in captioner's captions),
    its text-space appearance feature (the embedder's view embeddings, averaged and renormalised), and the
    background passage's embedding."""
    caption_embedder = embedder if isinstance(embedder, CaptionEmbedder) else CaptionEmbedder(text_encoder)
    captions = caption_embedder.track_captions(crops)
    features: dict[str, np.ndarray] = {}
    if crops:
        rows = embedder.embed(crops, captions) if embedder is caption_embedder else embedder.embed(crops)
        agg = aggregate_views([c.object_id for c in crops], rows)
        features = {oid: agg.features[i] for i, oid in enumerate(agg.object_ids)}
    background = (text_encoder.encode_passages([config.background_passage])[0]
                  if config.background_passage is not None else None)
    return _ObjectLooks(captions, features, background)


def _fit_scene_autoencoder(looks: _ObjectLooks, text_encoder: TextEncoder,
                           config: AlignmentConfig) -> tuple[FeatureAutoencoder, float]:
    """Step 4: the scene's ``FeatureAutoencoder`` ``D -> d`` fitted on the objects' features, the background
    passage and, with ``use_vocabulary``, the caption vocabulary. Returns it and its final loss."""
    fit_rows = [looks.features[o] for o in sorted(looks.features)]
    fit_rows += [looks.background] if looks.background is not None else []
    if not fit_rows:
        fit_rows = [np.zeros(text_encoder.dim, np.float32)]
    vocabulary = (text_encoder.encode_passages(appearance_vocabulary()) if config.use_vocabulary else None)
    autoencoder, report = FeatureAutoencoder.fit(np.stack(fit_rows), vocabulary, config.autoencoder_config(),
                                                 text_space=text_encoder.name)
    return autoencoder, report.final_loss


def _fit_appearance_field(graph: SceneGraph, log: SceneLog, maps: NodeIdMaps, objects: Sequence[NodeObject],
                          looks: _ObjectLooks, autoencoder: FeatureAutoencoder,
                          config: AlignmentConfig) -> _FittedField:
    """Step 5: per-Gaussian latents initialised from their node's latent (background Gaussians from the
    background passage's) and fitted by rendering against the node-id maps of every ``fit_frame_stride``-th
    frame; ``f_app`` per node decoded from the field as rendered on its own pixels (the Gaussians' mean for
    nodes the fit views miss). The graph passed in is not changed."""
    node_of = {o.object_id: o.node_id for o in objects}
    fitted_ids = [oid for oid in sorted(looks.features) if oid in node_of]
    latents = (autoencoder.encode(np.stack([looks.features[o] for o in fitted_ids])) if fitted_ids
               else np.zeros((0, config.feature_dim), np.float32))
    node_latents = {node_of[oid]: latents[i] for i, oid in enumerate(fitted_ids)}
    bg_text = looks.background
    z_bg = (autoencoder.encode(bg_text[None])[0] if bg_text is not None
            else np.zeros(config.feature_dim, np.float32))
    f_bg = bg_text if bg_text is not None else autoencoder.decode(z_bg[None])[0]
    views = feature_views(log, maps, frames=maps.frame_indices[::config.fit_frame_stride])
    fit = fit_feature_field(graph, views, node_latents, z_bg, config.fit_config(), autoencoder=autoencoder,
                            node_targets={node_of[o]: looks.features[o] for o in fitted_ids},
                            background_target=f_bg)
    metrics = dict(fit.summary())
    means = {**node_mean_features(fit.graph, set(node_latents) - set(fit.node_features)), **fit.node_features}
    f_app: dict[int, np.ndarray] = {}
    if means:
        ids = sorted(means)
        decoded = autoencoder.decode(np.stack([means[i] for i in ids]))
        f_app = {i: l2_normalise(decoded[k][None])[0] for k, i in enumerate(ids)}
        metrics["f_app_vs_caption_cosine"] = float(np.mean(
            [float(f_app[node_of[o]] @ looks.features[o]) for o in fitted_ids]))
    gaussian_feats = gaussian_features(fit.graph).cpu().numpy().astype(np.float32)
    return _FittedField(fit.graph, f_app, gaussian_feats, metrics)


def _motion_features(aligner: MotionAligner | None, log: SceneLog) -> dict[str, ObjectMotionFeatures]:
    """Step 6: ``object_id -> ObjectMotionFeatures`` of the log's movable objects (none without an aligner)."""
    return aligner.features(log) if aligner is not None else {}


def _node_languages(objects: Sequence[NodeObject], captions: dict[str, AppearanceCaption],
                    f_app: dict[int, np.ndarray], motion: dict[str, ObjectMotionFeatures]) -> tuple[NodeLanguage, ...]:
    """One ``NodeLanguage`` per object node: ``f_app`` and caption for objects with crops, motion features for
    movable ones."""
    nodes = []
    for obj in objects:
        kind = agent_kind(obj.category) or ""
        nodes.append(NodeLanguage(
            node_id=obj.node_id, object_id=obj.object_id, category=obj.category, kind=kind,
            f_app=f_app.get(obj.node_id) if obj.object_id in captions else None,
            caption=captions.get(obj.object_id),
            motion=motion.get(obj.object_id) if kind else None,
        ))
    return tuple(nodes)


def _node_counts(nodes: Sequence[NodeLanguage]) -> dict[str, float]:
    return {"object_nodes": float(len(nodes)),
            "nodes_with_f_app": float(sum(n.f_app is not None for n in nodes)),
            "nodes_with_motion": float(sum(n.motion is not None for n in nodes))}


def build_language_scene(
    graph: SceneGraph | None,
    log: SceneLog,
    *,
    text_encoder: TextEncoder,
    aligner: MotionAligner | None,
    embedder: AppearanceEmbedder | None = None,
    autoencoder: FeatureAutoencoder | None = None,
    config: AlignmentConfig = AlignmentConfig(),
    scene_hash: str = "",
) -> BuiltLanguageScene:
    """Language features of every object node of ``graph`` (see the module docstring).

    Args:
        graph: the reconstructed scene of ``log`` (its nodes' ``GaussianSet.features`` are replaced by
            the fitted latents, and the background latent is stored in its metadata); ``None`` only for
            logs without pixels.
        log: the sequence the graph was reconstructed from.
        text_encoder: the text space (captions and the background passage are embedded as passages).
        aligner: the trained trajectory aligner, or ``None`` (no motion features).
        embedder: crops -> text-space features; by default the one ``config.captioner`` names.
        autoencoder: a trained autoencoder to use instead of fitting one (its latent width must be
            ``config.feature_dim``).
        config: see ``AlignmentConfig``.
        scene_hash: the reconstruction's hash (stored in the scene).

    Raises:
        AlignmentConfigError: invalid config.
        ValueError: the log has pixels but no graph is given; the autoencoder's widths do not fit.
    """
    config.validate()
    started = time.perf_counter()
    clock = StageClock()  # seconds per stage: metrics time_<stage>_s
    metrics: dict[str, float] = {}
    objects = _object_nodes(graph, log)
    embedder = embedder or appearance_embedder(config.captioner, text_encoder)
    _check_autoencoder(autoencoder, config, text_encoder)
    with_pixels = _has_pixels(log)
    if with_pixels and graph is None:
        raise ValueError(f"{log.seq_id}: the log has images but no scene graph was given")

    maps: NodeIdMaps | None = None
    captions: dict[str, AppearanceCaption] = {}
    f_app: dict[int, np.ndarray] = {}
    gaussian_feats: np.ndarray | None = None
    metadata: dict[str, str] = {"embedder": embedder.name, "min_area": str(config.min_area)}
    if with_pixels:
        assert graph is not None
        with clock.stage("node_maps"):
            maps = render_node_id_maps(graph, log, backend=config.backend)
        metrics.update(_projected_mask_agreement(log, maps, graph, config))
        with clock.stage("crops"):
            crops = _crops_under_node_maps(log, maps, graph, config)
            metrics.update(_crop_counts(crops, config))
        with clock.stage("captions"):
            looks = _describe_objects(crops, embedder, text_encoder, config)
            captions = looks.captions
        with clock.stage("autoencoder"):
            if autoencoder is None:
                autoencoder, metrics["autoencoder_final_loss"] = _fit_scene_autoencoder(looks, text_encoder, config)
        with clock.stage("feature_field"):
            fitted = _fit_appearance_field(graph, log, maps, objects, looks, autoencoder, config)
            graph, f_app, gaussian_feats = fitted.graph, fitted.f_app, fitted.gaussian_features
            metrics.update(fitted.metrics)
        metadata.update({"autoencoder_latent_dim": str(autoencoder.latent_dim),
                         "background_passage": config.background_passage or ""})

    with clock.stage("motion"):
        motion = _motion_features(aligner, log)
    if aligner is not None:
        metadata["aligner"] = type(aligner).__name__

    nodes = _node_languages(objects, captions, f_app, motion)
    if maps is not None:
        frame_indices, cameras, node_maps = maps.frame_indices, maps.cameras, maps.maps
    else:
        frame_indices, cameras, node_maps = np.arange(log.num_frames, dtype=np.int64), (), None
    scene = LanguageScene(seq_id=log.seq_id, scene_hash=scene_hash, nodes=nodes, frame_indices=frame_indices,
                          cameras=tuple(cameras), node_id_maps=node_maps, text_encoder=text_encoder.name,
                          metadata=metadata)
    times = {**clock.seconds, "total": time.perf_counter() - started}
    metrics.update({f"time_{k}_s": float(v) for k, v in times.items()})
    metrics.update(_node_counts(nodes))
    logger.info("%s: language scene of %d object nodes (%d with appearance, %d with motion) in %.1f s",
                log.seq_id, len(nodes), int(metrics["nodes_with_f_app"]), int(metrics["nodes_with_motion"]),
                times["total"])
    return BuiltLanguageScene(scene=scene, gaussian_features=gaussian_feats, autoencoder=autoencoder,
                              captions=captions, metrics=metrics, graph=graph)


__all__ = [
    "BACKGROUND_PASSAGE",
    "AlignmentConfig",
    "AlignmentConfigError",
    "BuiltLanguageScene",
    "build_language_scene",
]
