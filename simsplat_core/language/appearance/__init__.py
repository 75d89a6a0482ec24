"""Appearance alignment (SIMSplat Sec. 3.2): what each object looks like, in the text space.

Per object and view, a mask (ground-truth instance ids, or a node's projected Gaussians) gives an
``ObjectCrop``; an ``AppearanceEmbedder`` maps crops to text-space features (by default the built-in
``Captioner`` writes "a red SUV" and a ``TextEncoder`` embeds it as a passage); the per-object
features are compressed to a few dimensions by a scene's ``FeatureAutoencoder`` before per-Gaussian
features are fitted by rendering.

    crops = crops_from_log(log)
    features = object_features(CaptionEmbedder(E5TextEncoder()), crops)   # [M, 384] per object
    ae, _ = FeatureAutoencoder.fit(features.features, vocabulary)         # 384 -> 8 -> 384

Modules: ``colors`` (colour naming), ``subtypes`` (size rules), ``captioner``, ``crops``,
``embedders``, ``clip_backend`` (image-text model on local weights), ``autoencoder``, ``vlm_captioner``.
Captioner accuracy against ground-truth attributes is ``simsplat_core.eval.captions``.
"""

from simsplat_core.language.appearance.autoencoder import (
    AutoencoderConfig,
    AutoencoderState,
    FeatureAutoencoder,
    reconstruction_cosine,
)
from simsplat_core.language.appearance.captioner import (
    AppearanceCaption,
    AppearanceCaptioner,
    Captioner,
    appearance_vocabulary,
    describe_object,
    describe_track,
)
from simsplat_core.language.appearance.clip_backend import AppearanceBackendUnavailable, OpenClipEmbedder
from simsplat_core.language.appearance.crops import ObjectCrop, crops_from_log
from simsplat_core.language.appearance.embedders import (
    AppearanceEmbedder,
    CaptionEmbedder,
    ObjectFeatures,
    aggregate_views,
    object_features,
)

__all__ = [
    "AppearanceBackendUnavailable",
    "AppearanceCaption",
    "AppearanceCaptioner",
    "AppearanceEmbedder",
    "AutoencoderConfig",
    "AutoencoderState",
    "Captioner",
    "CaptionEmbedder",
    "FeatureAutoencoder",
    "ObjectCrop",
    "ObjectFeatures",
    "OpenClipEmbedder",
    "aggregate_views",
    "appearance_vocabulary",
    "crops_from_log",
    "describe_object",
    "describe_track",
    "object_features",
    "reconstruction_cosine",
]
