"""``LanguageScene`` s built straight from a synthetic log's ground truth, without any reconstruction.

The upper bound of grounding with perfect masks (``bench/bench_grounding.py``'s diagnostic) and a quick
queryable scene for tests: per object of the log, one node with

* ``f_app``: the text encoder's *passage* embedding of the object's appearance caption, either the
  built-in captioner's (``describe_track`` over the object's ground-truth crops) or the world's own
  ground-truth caption (``ObjectInfo.attributes["caption_appearance"]``);
* ``motion``: features from a trained ``MotionAligner`` when one is given, else built from the
  trajectory auto-labels (``label_log``): convex weights with ``sharpness`` of the mass on the
  labelled class, ``f_mot`` / ``f_loc`` the matching combinations of the codebook prototypes;
* ``node_id_maps``: the ground-truth instance masks with instance ids replaced by node ids
  (background ``0``, the ``k``-th object of ``log.objects`` node ``k + 1``, as ``scene.init`` numbers them).

    scene = language_scene_from_log(log, encoder)
    scene.node(3).caption.text      # "a silver van"
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

import numpy as np

from simsplat_core.language.alignment.motion_training import MotionAligner
from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.language.appearance.crops import crops_from_log
from simsplat_core.language.appearance.embedders import CaptionEmbedder
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.motion_labels import MotionLabel, label_log
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage, ObjectMotionFeatures
from simsplat_core.language.text import TextEncoder, l2_normalise
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.types import ObjectInfo, SceneLog

AppearanceSource = Literal["captioner", "ground_truth"]


def node_ids_of(log: SceneLog) -> dict[str, int]:
    """``object_id -> node_id``: objects in log order from node 1 (node 0 is the background)."""
    return {obj.object_id: k + 1 for k, obj in enumerate(log.objects)}


def ground_truth_caption(obj: ObjectInfo) -> AppearanceCaption | None:
    """The world's appearance caption of ``obj`` as an ``AppearanceCaption`` (``None`` without one)."""
    attrs = obj.attributes
    text = attrs.get("caption_appearance")
    if not text:
        return None
    if obj.category == "pedestrian":
        upper, lower = attrs["upper_color"], attrs["lower_color"]
        return AppearanceCaption(text, obj.category, "adult", (upper, lower), upper, lower, 1.0)
    return AppearanceCaption(text, obj.category, attrs.get("subtype", "object"), (attrs["color"],), confidence=1.0)


def captioner_captions(log: SceneLog, text_encoder: TextEncoder, min_area: int = 30) -> dict[str, AppearanceCaption]:
    """The built-in captioner's caption of every object with at least one crop of ``min_area`` pixels.

    30 pixels is the grounding benchmark's "visible in a frame"; with 100 (the crops' default) only about
    60 % of its well-visible objects got a caption on 240x160 images, with 30 all but a few.
    """
    return CaptionEmbedder(text_encoder).track_captions(crops_from_log(log, min_area=min_area))


def _one_hot(classes: tuple[str, ...], label: str, sharpness: float) -> np.ndarray:
    """``[K]`` convex weights: ``sharpness`` on ``label``, the rest spread evenly over the other classes."""
    w = np.full(len(classes), (1.0 - sharpness) / max(len(classes) - 1, 1))
    w[classes.index(label)] = sharpness if len(classes) > 1 else 1.0
    return w


def label_motion_features(
    labels: Mapping[str, MotionLabel], codebooks: MotionCodebooks, sharpness: float = 0.9
) -> dict[str, ObjectMotionFeatures]:
    """Motion features as a perfectly trained aligner would give them: convex weights peaked on the auto-labels.

    ``f_mot = sum_k w_k p_k`` over the kind's motion prototypes, ``f_loc = 1/2 (sum_s w_s p_s +
    sum_c w_c p_c)`` over sector and context prototypes (``language.alignment.motion_training``), each ``[D]`` float32.
    """
    out = {}
    for oid, label in labels.items():
        book = codebooks.motion(label.kind)
        w_mot = _one_hot(book.classes, label.motion, sharpness)
        w_sec = _one_hot(codebooks.sector.classes, label.sector, sharpness)
        w_ctx = _one_hot(codebooks.context.classes, label.context, sharpness)
        f_mot = (w_mot @ book.prototypes).astype(np.float32)
        f_loc = (0.5 * (w_sec @ codebooks.sector.prototypes + w_ctx @ codebooks.context.prototypes)).astype(np.float32)
        w_loc = 0.5 * np.concatenate([w_sec, w_ctx])
        out[oid] = ObjectMotionFeatures(
            object_id=oid,
            kind=label.kind,
            f_mot=f_mot,
            f_loc=f_loc,
            motion_probs=dict(zip(book.classes, map(float, w_mot))),
            location_probs=dict(zip(codebooks.location_classes, map(float, w_loc))),
            labels=label,
        )
    return out


def node_id_maps_from_log(
    log: SceneLog, node_ids: Mapping[str, int]
) -> tuple[np.ndarray, tuple[str, ...], np.ndarray] | None:
    """``(frame_indices [F], cameras, node_id_maps [F, C, H, W] int32)`` from the ground-truth instance masks.

    Instance ids become node ids; background (instance 0) becomes node 0. ``None`` when the log has
    no instance masks.
    """
    images = [img for img in log.images if img.instance is not None]
    if not images:
        return None
    frames = sorted({img.frame_idx for img in images})
    cameras = tuple(dict.fromkeys(img.camera for img in images))
    height, width = images[0].height, images[0].width
    lut_size = max([o.instance_id for o in log.objects] + [0]) + 1
    lut = np.zeros(lut_size, dtype=np.int32)
    for obj in log.objects:
        lut[obj.instance_id] = node_ids[obj.object_id]
    maps = np.full((len(frames), len(cameras), height, width), -1, dtype=np.int32)
    f_index = {f: i for i, f in enumerate(frames)}
    c_index = {c: i for i, c in enumerate(cameras)}
    for img in images:
        maps[f_index[img.frame_idx], c_index[img.camera]] = lut[img.instance]
    return np.asarray(frames, dtype=np.int64), cameras, maps


def language_scene_from_log(
    log: SceneLog,
    text_encoder: TextEncoder,
    appearance: AppearanceSource = "captioner",
    aligner: MotionAligner | None = None,
    codebooks: MotionCodebooks | None = None,
    sharpness: float = 0.9,
) -> LanguageScene:
    """A ``LanguageScene`` of ``log`` from ground truth (module docstring).

    Args:
        log: a log with object tracks; with images and instance masks for ``"captioner"`` captions and
            for node-id maps.
        text_encoder: embeds the captions (passages); the scene's features live in its space.
        appearance: ``"captioner"`` (built-in captioner on ground-truth crops; objects without crops get
            no ``f_app``) or ``"ground_truth"`` (the world's appearance captions).
        aligner: a trained motion aligner; ``None`` builds features from the auto-labels instead.
        codebooks: prototypes for label-built features (built from ``text_encoder`` when ``None``).
        sharpness: weight of the labelled class in label-built features.
    """
    if appearance == "captioner":
        captions = captioner_captions(log, text_encoder)
    elif appearance == "ground_truth":
        captions = {o.object_id: c for o in log.objects if (c := ground_truth_caption(o)) is not None}
    else:
        raise ValueError(f"appearance must be 'captioner' or 'ground_truth', got {appearance!r}")
    if aligner is not None:
        motion = aligner.features(log)
    else:
        books = codebooks or MotionCodebooks.build(text_encoder)
        motion = label_motion_features(label_log(log), books, sharpness)
    ids = node_ids_of(log)
    texts = [captions[o.object_id].text for o in log.objects if o.object_id in captions]
    embedded = dict(zip(texts, l2_normalise(text_encoder.encode_passages(texts)))) if texts else {}
    nodes = []
    for obj in log.objects:
        cap = captions.get(obj.object_id)
        nodes.append(
            NodeLanguage(
                node_id=ids[obj.object_id],
                object_id=obj.object_id,
                category=obj.category,
                kind=agent_kind(obj.category) or "",
                f_app=None if cap is None else embedded[cap.text],
                caption=cap,
                motion=motion.get(obj.object_id),
            )
        )
    rendered = node_id_maps_from_log(log, ids)
    frames, cameras, maps = rendered if rendered is not None else (np.zeros(0, np.int64), (), None)
    return LanguageScene(
        seq_id=log.seq_id,
        scene_hash="",
        nodes=tuple(nodes),
        frame_indices=frames,
        cameras=cameras,
        node_id_maps=maps,
        text_encoder=text_encoder.name,
        metadata={"source": f"ground-truth/{appearance}", "motion": "aligner" if aligner else "labels"},
    )


__all__ = [
    "AppearanceSource",
    "captioner_captions",
    "ground_truth_caption",
    "label_motion_features",
    "language_scene_from_log",
    "node_id_maps_from_log",
    "node_ids_of",
]
