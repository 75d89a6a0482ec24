"""Motion and location codebooks whose prototypes are text embeddings, and convex aggregation over them.

Prototype ``k`` of a codebook is the L2-normalised mean of the E5 *passage* embeddings of class
``k``'s prototype phrasings (``vocabulary.py``). Prototypes are **fixed**: they are the text anchors
that free-form queries are compared with, so letting them drift would silently move the motion
features out of the encoder's text space (and stale every stored feature when retrained). The
encoder learns only the convex weights.

An object's aggregated feature is a convex combination ``f = sum_k w_k p_k`` (``w`` = softmax of
the encoder's logits), so ``f`` lives in the text space (``D = 384`` for E5) and is compared with an
encoded query by cosine.

E5 embeddings are anisotropic: the phrases of one codebook have raw cosines of 0.8-0.95 with each
other. The training loss therefore measures cosine distance after subtracting the codebook group's
prototype mean (``centre``), a fixed affine map that spreads the classes apart (the common
"all-but-the-top" post-processing). ``centred_cosine`` is that measure.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.language.text import TextEncoder, l2_normalise
from simsplat_core.scenario.vocabulary import (
    LOCATION_CONTEXT,
    LOCATION_SECTOR,
    PEDESTRIAN_MOTION,
    VEHICLE_MOTION,
    Vocabulary,
)


@dataclass(frozen=True)
class Codebook:
    """Prototypes of one vocabulary.

    Attributes:
        name: vocabulary name.
        classes: ``K`` class names, in prototype order.
        prototypes: ``[K, D]`` float32 unit vectors.
    """

    name: str
    classes: tuple[str, ...]
    prototypes: np.ndarray

    def __len__(self) -> int:
        return len(self.classes)

    def index(self, name: str) -> int:
        return self.classes.index(name)


def build_codebook(vocabulary: Vocabulary, encoder: TextEncoder) -> Codebook:
    """Prototype ``k`` = normalised mean passage embedding of class ``k``'s phrasings."""
    prototypes = np.stack(
        [l2_normalise(encoder.encode_passages(list(c.prototypes))).mean(axis=0) for c in vocabulary.classes]
    )
    return Codebook(vocabulary.name, vocabulary.names, l2_normalise(prototypes))


def convex_combination(weights: torch.Tensor, prototypes: torch.Tensor) -> torch.Tensor:
    """``[N, D]`` features ``weights @ prototypes`` for ``[N, K]`` convex ``weights`` and ``[K, D]`` prototypes."""
    return weights @ prototypes


def centred_cosine(a: torch.Tensor, b: torch.Tensor, centre: torch.Tensor, eps: float = 1e-6) -> torch.Tensor:
    """Row-wise cosine ``[N]`` of ``[N, D]`` ``a`` and ``b`` after subtracting ``centre`` ``[D]`` from both."""
    a = a - centre
    b = b - centre
    return (a * b).sum(-1) / (a.norm(dim=-1) * b.norm(dim=-1)).clamp_min(eps)


def cosine_scores(features: np.ndarray, query: np.ndarray) -> np.ndarray:
    """``[N]`` cosine of ``[N, D]`` features with one ``[D]`` query (zero features score 0)."""
    return l2_normalise(np.asarray(features, dtype=np.float32)) @ l2_normalise(np.asarray(query)[None])[0]


@dataclass(frozen=True)
class MotionCodebooks:
    """The aligner's codebooks: one motion codebook per agent kind, the shared location codebook.

    The location codebook is ``sector + context`` prototypes; an object's location weights put half
    their mass on its sector and half on its context. Centres: ``motion_centre`` is the mean of all
    motion prototypes (both kinds, so scores stay comparable across kinds), ``location_centre`` the
    mean of all location prototypes.

    Attributes:
        encoder_name: ``TextEncoder.name`` of the text space.
        vehicle, pedestrian, sector, context: the codebooks.
    """

    encoder_name: str
    vehicle: Codebook
    pedestrian: Codebook
    sector: Codebook
    context: Codebook

    @classmethod
    def build(cls, encoder: TextEncoder) -> MotionCodebooks:
        vocabularies = (VEHICLE_MOTION, PEDESTRIAN_MOTION, LOCATION_SECTOR, LOCATION_CONTEXT)
        # one batch for every phrase (the encoder's cache then serves the per-class lookups)
        encoder.encode_passages([p for v in vocabularies for c in v.classes for p in c.prototypes])
        return cls(encoder.name, *(build_codebook(v, encoder) for v in vocabularies))

    def motion(self, kind: str) -> Codebook:
        """The motion codebook of ``"vehicle"`` or ``"pedestrian"``."""
        if kind == "vehicle":
            return self.vehicle
        if kind == "pedestrian":
            return self.pedestrian
        raise KeyError(f"no motion codebook for kind {kind!r}")

    @property
    def dim(self) -> int:
        return int(self.vehicle.prototypes.shape[1])

    @property
    def location_classes(self) -> tuple[str, ...]:
        return self.sector.classes + self.context.classes

    @property
    def location_prototypes(self) -> np.ndarray:
        """``[Ks + Kc, D]``."""
        return np.concatenate([self.sector.prototypes, self.context.prototypes])

    @property
    def motion_centre(self) -> np.ndarray:
        return np.concatenate([self.vehicle.prototypes, self.pedestrian.prototypes]).mean(axis=0)

    @property
    def location_centre(self) -> np.ndarray:
        return self.location_prototypes.mean(axis=0)

    def arrays(self) -> dict[str, np.ndarray]:
        """Prototypes by codebook name, for persistence."""
        return {cb.name: cb.prototypes for cb in (self.vehicle, self.pedestrian, self.sector, self.context)}

    @classmethod
    def from_arrays(cls, encoder_name: str, classes: dict[str, tuple[str, ...]],
                    arrays: dict[str, np.ndarray]) -> MotionCodebooks:
        """Inverse of ``arrays`` (``classes`` maps codebook name to class names)."""
        books = {
            name: Codebook(name, tuple(classes[name]), np.asarray(arrays[name], dtype=np.float32))
            for name in (VEHICLE_MOTION.name, PEDESTRIAN_MOTION.name, LOCATION_SECTOR.name, LOCATION_CONTEXT.name)
        }
        return cls(
            encoder_name,
            books[VEHICLE_MOTION.name],
            books[PEDESTRIAN_MOTION.name],
            books[LOCATION_SECTOR.name],
            books[LOCATION_CONTEXT.name],
        )
