"""A reconstructed scene in the language space: what grounding reads.

``LanguageScene`` is the contract between the alignment stage (which builds it from a scene graph, its
log and the trained models) and the ``QueryEngine`` / grounding benchmark (which only read it). It holds
per object node the language features of SIMSplat Sec. 3.2 and, per frame and camera, the node-id maps
rendered from the scene's Gaussians, from which every per-frame pixel mask is cut.

Shapes: ``D`` is the text space's width (384 for E5), ``F`` frames, ``C`` cameras, ``H x W`` pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable

import numpy as np

from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.language.motion_training import ObjectMotionFeatures


@dataclass(frozen=True)
class NodeLanguage:
    """Language features of one object node.

    Attributes:
        node_id: the scene-graph node.
        object_id: the log's object (track) id.
        category: ``types.CATEGORIES`` value (vehicle, pedestrian, cyclist, sign, cone, barrier, ...).
        kind: motion codebook, ``"vehicle"`` / ``"pedestrian"``, or ``""`` for static objects.
        f_app: ``[D]`` float32 unit appearance feature in the text space (decoded from the node's fitted
            per-Gaussian features), or ``None`` when the log has no pixels of the object.
        caption: the captioner's description of the object (``None`` without pixels).
        motion: motion/location features from the trajectory aligner (``None`` for static objects).
    """

    node_id: int
    object_id: str
    category: str
    kind: str
    f_app: np.ndarray | None
    caption: AppearanceCaption | None
    motion: ObjectMotionFeatures | None

    @property
    def f_mot(self) -> np.ndarray | None:
        """``[D]`` motion feature (or ``None``)."""
        return None if self.motion is None else self.motion.f_mot

    @property
    def f_loc(self) -> np.ndarray | None:
        """``[D]`` location feature (or ``None``)."""
        return None if self.motion is None else self.motion.f_loc


@dataclass(frozen=True, eq=False)
class LanguageScene:
    """One sequence's object nodes with language features and rendered node-id maps.

    Attributes:
        seq_id: the sequence.
        scene_hash: the reconstruction it was built from (``""`` for scenes built straight from a log).
        nodes: one entry per object node (background excluded).
        frame_indices: ``[F]`` int64 frames of ``node_id_maps``.
        cameras: the ``C`` camera names of ``node_id_maps``.
        node_id_maps: ``[F, C, H, W]`` int32 node of largest compositing weight per pixel, ``-1`` where
            nothing opaque was hit (``SceneRender.node_id``); ``None`` for logs without cameras.
        text_encoder: name of the text encoder whose space the features live in.
        metadata: free-form string facts (aligner / autoencoder hashes, ...).
    """

    seq_id: str
    scene_hash: str
    nodes: tuple[NodeLanguage, ...]
    frame_indices: np.ndarray
    cameras: tuple[str, ...]
    node_id_maps: np.ndarray | None
    text_encoder: str
    metadata: dict[str, str] = field(default_factory=dict)

    def node(self, node_id: int) -> NodeLanguage:
        for n in self.nodes:
            if n.node_id == node_id:
                return n
        raise KeyError(f"{self.seq_id}: no object node {node_id}")

    def masks(self, node_ids: Iterable[int]) -> np.ndarray:
        """``[F, C, H, W]`` bool: pixels whose node is one of ``node_ids``.

        Raises:
            ValueError: the scene has no node-id maps (a log without cameras).
        """
        if self.node_id_maps is None:
            raise ValueError(f"{self.seq_id}: the scene has no rendered node-id maps (no cameras)")
        return np.isin(self.node_id_maps, np.asarray(list(node_ids), dtype=np.int32))

    def busiest_frame(self, masks: np.ndarray) -> int:
        """The frame where ``masks`` (``[F, C, H, W]`` bool, e.g. from ``masks``) cover the most pixels; the
        middle frame when they cover none."""
        counts = np.asarray(masks).reshape(len(self.frame_indices), -1).sum(axis=1)
        row = int(np.argmax(counts)) if counts.size and counts.max() > 0 else len(self.frame_indices) // 2
        return int(self.frame_indices[row])
