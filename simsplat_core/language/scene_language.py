"""A reconstructed scene in the language space: what grounding reads.

``LanguageScene`` is the contract between the alignment stage (which builds it from a scene graph, its
log and the trained models) and the ``QueryEngine`` / grounding benchmark (which only read it). It holds
per object node the language features of SIMSplat Sec. 3.2 (``NodeLanguage``; its motion and location part,
``ObjectMotionFeatures``, is what ``alignment.motion_training.MotionAligner.features`` returns) and, per frame
and camera, the node-id maps rendered from the scene's Gaussians, from which every per-frame pixel mask is cut.
Both ``language.alignment`` and ``language.grounding`` import this module; it imports neither.

Shapes: ``D`` is the text space's width (384 for E5), ``F`` frames, ``C`` cameras, ``H x W`` pixels.

**Derived data, never silently stale.** The node-id maps are rendered from one scene graph. A scene
records the ``SceneGraph.revision`` it describes (``graph_revision``) and the one its maps were rendered
from (``maps_revision``); ``""`` is a reconstructed / stored graph. An edited graph (``graph.without``,
``with_node``, ``with_poses``) has a new revision: :meth:`LanguageScene.for_graph` derives the scene of
the edited graph, re-rendering the maps when given the log, otherwise carrying them as invalid, and
``masks`` then raises instead of returning masks of the old scene. :meth:`LanguageScene.check_graph`
tells whether a scene belongs to a given graph.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.language.motion_labels import MotionLabel
from simsplat_core.language.node_masks import render_node_id_maps
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.types import SceneLog


class StaleSceneError(ValueError):
    """Data derived from one scene graph was asked for another (edited) graph; the message says which."""


@dataclass(frozen=True)
class ObjectMotionFeatures:
    """Motion/location language features of one object.

    Attributes:
        object_id, kind: the object and its motion codebook (``"vehicle"`` / ``"pedestrian"``).
        f_mot: ``[D]`` float32 convex combination of the kind's motion prototypes.
        f_loc: ``[D]`` float32 convex combination of the location prototypes.
        motion_probs: convex weights by motion class (sum 1).
        location_probs: convex weights by location class, sectors then contexts (sum 1; each group 1/2).
        labels: the auto-labels of the object's whole trajectory.
    """

    object_id: str
    kind: str
    f_mot: np.ndarray
    f_loc: np.ndarray
    motion_probs: dict[str, float]
    location_probs: dict[str, float]
    labels: MotionLabel

    @property
    def motion(self) -> str:
        """Most likely motion class."""
        return max(self.motion_probs, key=self.motion_probs.__getitem__)


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
        static_location: for a static object, the share of its steps in each ego-relative sector
            (``language.grounding.static_location``; derived from the log when scene and log meet, not stored).
    """

    node_id: int
    object_id: str
    category: str
    kind: str
    f_app: np.ndarray | None
    caption: AppearanceCaption | None
    motion: ObjectMotionFeatures | None
    static_location: dict[str, float] | None = None

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
        graph_revision: ``SceneGraph.revision`` of the graph whose nodes the scene describes.
        maps_revision: revision of the graph ``node_id_maps`` were rendered from; the maps are valid only
            when it equals ``graph_revision`` (see the module docstring).
    """

    seq_id: str
    scene_hash: str
    nodes: tuple[NodeLanguage, ...]
    frame_indices: np.ndarray
    cameras: tuple[str, ...]
    node_id_maps: np.ndarray | None
    text_encoder: str
    metadata: dict[str, str] = field(default_factory=dict)
    graph_revision: str = ""
    maps_revision: str = ""

    @property
    def maps_valid(self) -> bool:
        """Whether ``node_id_maps`` were rendered from the graph the scene describes."""
        return self.maps_revision == self.graph_revision

    def check_graph(self, graph: SceneGraph) -> None:
        """Raise :class:`StaleSceneError` unless the scene describes ``graph`` (same revision)."""
        if graph.revision != self.graph_revision:
            raise StaleSceneError(f"{self.seq_id}: the language scene describes graph revision "
                                  f"{self.graph_revision or '(stored)'!r}, not {graph.revision or '(stored)'!r}; "
                                  f"derive it with LanguageScene.for_graph(graph, log)")

    def for_graph(self, graph: SceneGraph, log: SceneLog | None = None, *,
                  new_nodes: Mapping[int, NodeLanguage] | None = None, backend: str = "auto") -> LanguageScene:
        """The scene of ``graph``, an edit of the graph this scene describes (this scene is not changed).

        Nodes the graph no longer has are dropped; its object nodes the scene does not know get
        ``new_nodes[node_id]`` or, without one, an entry with no language features. With ``log`` (the
        cameras of the maps) the node-id maps are re-rendered from ``graph`` at the scene's frames;
        without it they are kept but marked invalid (``masks`` raises) unless the graph is the one they
        were rendered from.

        Raises:
            ValueError: a ``new_nodes`` entry names another node id than its key, or the re-rendered maps
                have other cameras than the scene's.
        """
        known = {n.node_id: n for n in self.nodes}
        extra = dict(new_nodes or {})
        nodes = []
        for obj in graph.object_nodes:
            entry = extra.pop(obj.node_id, None) or known.get(obj.node_id)
            if entry is None:
                entry = NodeLanguage(obj.node_id, obj.object_id, obj.category, "", None, None, None)
            if entry.node_id != obj.node_id:
                raise ValueError(f"{self.seq_id}: new_nodes[{obj.node_id}] describes node {entry.node_id}")
            nodes.append(entry)
        if extra:
            raise ValueError(f"{self.seq_id}: new_nodes {sorted(extra)} are not object nodes of the graph")
        maps, maps_revision = self.node_id_maps, self.maps_revision
        if log is not None and self.node_id_maps is not None and graph.revision != self.maps_revision:
            rendered = render_node_id_maps(graph, log, self.frame_indices, backend=backend)
            if rendered.cameras != tuple(self.cameras) or rendered.maps.shape != self.node_id_maps.shape:
                raise ValueError(f"{self.seq_id}: the log's cameras {rendered.cameras} do not match the scene's "
                                 f"{self.cameras}")
            maps, maps_revision = rendered.maps, graph.revision
        return dataclasses.replace(self, nodes=tuple(nodes), node_id_maps=maps, graph_revision=graph.revision,
                                   maps_revision=maps_revision)

    def node(self, node_id: int) -> NodeLanguage:
        for n in self.nodes:
            if n.node_id == node_id:
                return n
        raise KeyError(f"{self.seq_id}: no object node {node_id}")

    def masks(self, node_ids: Iterable[int]) -> np.ndarray:
        """``[F, C, H, W]`` bool: pixels whose node is one of ``node_ids``.

        Raises:
            ValueError: the scene has no node-id maps (a log without cameras).
            StaleSceneError: the maps were rendered from another graph than the one the scene describes.
        """
        if self.node_id_maps is None:
            raise ValueError(f"{self.seq_id}: the scene has no rendered node-id maps (no cameras)")
        if not self.maps_valid:
            raise StaleSceneError(f"{self.seq_id}: the node-id maps were rendered from graph revision "
                                  f"{self.maps_revision or '(stored)'!r} but the scene describes the edited revision "
                                  f"{self.graph_revision!r}; re-render them with LanguageScene.for_graph(graph, log)")
        return np.isin(self.node_id_maps, np.asarray(list(node_ids), dtype=np.int32))

    def busiest_frame(self, masks: np.ndarray) -> int:
        """The frame where ``masks`` (``[F, C, H, W]`` bool, e.g. from ``masks``) cover the most pixels; the
        middle frame when they cover none."""
        counts = np.asarray(masks).reshape(len(self.frame_indices), -1).sum(axis=1)
        row = int(np.argmax(counts)) if counts.size and counts.max() > 0 else len(self.frame_indices) // 2
        return int(self.frame_indices[row])
