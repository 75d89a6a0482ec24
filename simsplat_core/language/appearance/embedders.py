"""Appearance embedders: object crops -> features in a text space, one row per crop.

Two families plug into the same protocol:

* ``CaptionEmbedder`` (default): caption each crop (built-in ``Captioner`` or any
  ``AppearanceCaptioner``) and embed the caption with a ``TextEncoder`` as a *passage* (stored,
  scene-side text; user descriptions are embedded as queries) -- the 4D LangSplat recipe, which puts
  appearance in the same space as motion and location features.
* ``clip_backend.OpenClipEmbedder``: an image-text model's image tower on user-supplied weights.

``appearance_embedder(captioner, text_encoder)`` builds the caption embedder a pipeline config names:
``"builtin"`` (the rule-based captioner) or ``"vlm"`` (``vlm_captioner.VlmCaptioner`` on the
OpenAI-compatible endpoint of ``SIMSPLAT_VLM_URL`` / ``SIMSPLAT_VLM_MODEL``, one request per object).

``object_features`` averages a crop-level embedder's rows per object (renormalised), keeping the
per-view rows too.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from simsplat_core.language.appearance.captioner import AppearanceCaption, AppearanceCaptioner, Captioner
from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.language.text import TextEncoder, l2_normalise

logger = logging.getLogger(__name__)


@runtime_checkable
class AppearanceEmbedder(Protocol):
    """Object crops -> ``[N, dim]`` float32 unit rows in some text space.

    Attributes:
        name: identifies the embedder and its space (features of different names are not comparable).
        dim: feature width ``D``.
    """

    name: str
    dim: int

    def embed(self, crops: Sequence[ObjectCrop]) -> np.ndarray:
        """``[N, dim]`` features, one per crop, in input order."""
        ...


@dataclass(frozen=True, eq=False)
class ObjectFeatures:
    """Per-object appearance features and the per-view features they average.

    Attributes:
        object_ids: ``[M]`` objects in first-seen order.
        features: ``[M, D]`` float32 unit rows (mean of the object's view features, renormalised).
        view_features: ``[N, D]`` float32 per-crop features, in crop order.
        view_object: ``[N]`` int64 row of ``object_ids`` each crop belongs to.
    """

    object_ids: tuple[str, ...]
    features: np.ndarray
    view_features: np.ndarray
    view_object: np.ndarray

    def feature(self, object_id: str) -> np.ndarray:
        """``[D]`` feature of one object."""
        return self.features[self.object_ids.index(object_id)]


def aggregate_views(
    object_ids: Sequence[str], view_features: np.ndarray, weights: np.ndarray | None = None
) -> ObjectFeatures:
    """Average per-view features ``[N, D]`` per object (optionally weighted, e.g. by mask area) and renormalise."""
    view_features = np.asarray(view_features, dtype=np.float32)
    if len(object_ids) != view_features.shape[0]:
        raise ValueError(f"{len(object_ids)} object ids for {view_features.shape[0]} feature rows")
    ids = tuple(dict.fromkeys(object_ids))
    index = {oid: i for i, oid in enumerate(ids)}
    rows = np.array([index[o] for o in object_ids], dtype=np.int64)
    w = np.ones(len(rows), np.float32) if weights is None else np.asarray(weights, dtype=np.float32)
    sums = np.zeros((len(ids), view_features.shape[1]), dtype=np.float64)
    np.add.at(sums, rows, view_features * w[:, None])
    return ObjectFeatures(ids, l2_normalise(sums), view_features, rows)


def object_features(embedder: AppearanceEmbedder, crops: Sequence[ObjectCrop]) -> ObjectFeatures:
    """Embed every crop with ``embedder`` and average per object (plain mean, renormalised)."""
    return aggregate_views([c.object_id for c in crops], embedder.embed(crops))


class CaptionEmbedder:
    """Caption-then-embed: ``embed(crops)`` = ``text_encoder.encode_passages(captions)``.

    Args:
        text_encoder: any ``TextEncoder`` (E5 by default elsewhere in the pipeline).
        captioner: any ``AppearanceCaptioner``; the built-in rule-based ``Captioner()`` by default.
        per_view: caption every crop on its own (default); ``False`` captions each object once from all
            its crops (``describe_track``) and gives every crop of it that caption -- one request per
            object instead of one per view for captioners that cost a model call (a VLM).
    """

    def __init__(self, text_encoder: TextEncoder, captioner: AppearanceCaptioner | None = None,
                 per_view: bool = True) -> None:
        self.text_encoder = text_encoder
        self.captioner = captioner or Captioner()
        self.per_view = per_view
        self.dim = int(text_encoder.dim)
        self.name = f"caption[{self.captioner.name}{'' if per_view else ',per-object'}]>{text_encoder.name}"

    def captions(self, crops: Sequence[ObjectCrop],
                 track_captions: Mapping[str, AppearanceCaption] | None = None) -> list[AppearanceCaption]:
        """One caption per crop (the object's track caption for every crop when not ``per_view``; pass
        ``track_captions`` when they were already made)."""
        if not self.per_view:
            tracks = self.track_captions(crops) if track_captions is None else track_captions
            return [tracks[c.object_id] for c in crops]
        return [self.captioner.describe(c) for c in crops]

    def embed(self, crops: Sequence[ObjectCrop],
              track_captions: Mapping[str, AppearanceCaption] | None = None) -> np.ndarray:
        """``[N, D]`` passage embeddings of the crops' captions (``track_captions`` as in ``captions``)."""
        if not crops:
            return np.zeros((0, self.dim), dtype=np.float32)
        return self.text_encoder.encode_passages([c.text for c in self.captions(crops, track_captions)])

    def track_captions(self, crops: Sequence[ObjectCrop]) -> dict[str, AppearanceCaption]:
        """``object_id -> caption`` voted over each object's crops (``describe_track``)."""
        by_object: dict[str, list[ObjectCrop]] = {}
        for crop in crops:
            by_object.setdefault(crop.object_id, []).append(crop)
        return {oid: self.captioner.describe_track(views) for oid, views in by_object.items()}


#: Captioners a pipeline config can name (``appearance_embedder``).
CAPTIONERS: tuple[str, ...] = ("builtin", "vlm")


def appearance_embedder(captioner: str, text_encoder: TextEncoder) -> CaptionEmbedder:
    """The caption embedder named by a config (module docstring).

    Raises:
        ValueError: an unknown captioner name.
        VLMError: ``"vlm"`` without ``SIMSPLAT_VLM_URL`` / ``SIMSPLAT_VLM_MODEL`` in the environment.
    """
    if captioner == "builtin":
        return CaptionEmbedder(text_encoder)
    if captioner == "vlm":
        # imported on use: only this captioner needs the VLM client (and grounding's parser)
        from simsplat_core.language.appearance.vlm_captioner import VlmCaptioner  # noqa: PLC0415
        from simsplat_core.vlm import OpenAIChatClient, OpenAIChatConfig  # noqa: PLC0415

        return CaptionEmbedder(text_encoder, VlmCaptioner(OpenAIChatClient(OpenAIChatConfig.from_env())),
                               per_view=False)
    raise ValueError(f"unknown captioner {captioner!r}: expected one of {', '.join(CAPTIONERS)}")
