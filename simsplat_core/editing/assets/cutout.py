"""Assets cut out of a reconstructed scene: its vehicle and pedestrian nodes that are good enough.

    assets, report = cutout_assets(graph, log.objects, log.tracks, seq_id=log.seq_id, language=scene)
    print("\\n".join(report.lines()))

**Filter** (``CutoutConfig``, every decision reported in ``CutoutReport``): a node of an allowed category
is kept when the log's cameras saw it in at least ``min_visible_frames`` frames (``Track.visible``) and,
after cleaning, at least ``min_gaussians`` Gaussians remain, ``min_inside_share`` of its opaque
Gaussians lying in its box, and its mean side coverage (``editing.assets.quality.side_coverage``, after
mirroring) is at least ``min_coverage``. **Cleaning** drops Gaussians fainter than ``min_opacity`` and
those whose centre lies outside the box grown by ``box_margin`` of each half-size (floaters a
reconstruction attached to the node). A vehicle seen from one flank only is completed by mirroring
(``mirror_vehicles``, ``editing.assets.quality.mirror_completed``). The coverages go into the asset's
attributes (``coverage_front`` ... ``coverage``): retrieval prefers complete assets.

**Metadata.** The box is the median track box over the frames the object was seen. Caption, subtype
and colours come from the language scene's caption of the node when there is one (what grounding
uses), else from the log's object attributes (``subtype``, ``color`` / ``upper_color``,
``lower_color``), else from the built-in captioner looking at renders of the asset itself
(``editing.assets.render.describe_asset``). A pedestrian keeps its deformation: the offsets at the node's deform
frames and the distance walked up to each (from the node's poses).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import torch

from simsplat_core.editing.assets.quality import mirror_completed, side_coverage
from simsplat_core.editing.assets.record import LOWER_COLOR, Asset
from simsplat_core.editing.assets.render import describe_asset
from simsplat_core.language.appearance.captioner import AppearanceCaption, caption_text
from simsplat_core.language.appearance.colors import UNKNOWN
from simsplat_core.language.appearance.subtypes import subtype_from_size
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.scene.nodes import OFFSETS, NonRigidNode, ObjectNode
from simsplat_core.types import ObjectInfo, Track

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class CutoutConfig:
    """Which nodes become assets (see the module docstring)."""

    categories: tuple[str, ...] = ("vehicle", "pedestrian")
    min_visible_frames: int = 8
    min_gaussians: int = 200
    min_inside_share: float = 0.6
    min_coverage: float = 0.5
    min_opacity: float = 0.05
    box_margin: float = 0.1
    mirror_vehicles: bool = True


@dataclass(frozen=True)
class CutoutDecision:
    """The filter's verdict on one node.

    Attributes:
        object_id, node_id, category: the node.
        kept: whether it became an asset.
        reason: why not (``""`` when kept).
        visible_frames: frames a camera saw the object in.
        gaussians: Gaussians kept by the cleaning / the node's total (mirroring adds more).
        inside_share: share of the node's opaque Gaussians inside its box.
        coverage: mean side coverage after mirroring (``editing.assets.quality.side_coverage``).
        mirrored: ``"left->right"`` / ``"right->left"`` when a flank was mirrored, else ``""``.
    """

    object_id: str
    node_id: int
    category: str
    kept: bool
    reason: str
    visible_frames: int
    gaussians: tuple[int, int]
    inside_share: float
    coverage: float = 0.0
    mirrored: str = ""


@dataclass(frozen=True)
class CutoutReport:
    """Every decision of one scene's cut-out, with the filter used."""

    seq_id: str
    config: CutoutConfig
    decisions: tuple[CutoutDecision, ...] = field(default_factory=tuple)

    @property
    def kept(self) -> list[CutoutDecision]:
        return [d for d in self.decisions if d.kept]

    @property
    def rejected(self) -> list[CutoutDecision]:
        return [d for d in self.decisions if not d.kept]

    def lines(self) -> list[str]:
        """One line per node, for logs and the CLI."""
        cfg = self.config
        out = [f"{self.seq_id}: kept {len(self.kept)} of {len(self.decisions)} {'/'.join(cfg.categories)} nodes "
               f"(seen in >= {cfg.min_visible_frames} frames, >= {cfg.min_gaussians} Gaussians after cleaning, "
               f">= {cfg.min_inside_share:.0%} inside the box, side coverage >= {cfg.min_coverage})"]
        for d in self.decisions:
            verdict = "kept" if d.kept else f"rejected: {d.reason}"
            mirrored = f", mirrored {d.mirrored}" if d.mirrored else ""
            out.append(f"  node {d.node_id} {d.object_id} ({d.category}): {d.visible_frames} frames seen, "
                       f"{d.gaussians[0]}/{d.gaussians[1]} Gaussians, {d.inside_share:.0%} inside, coverage "
                       f"{d.coverage:.2f}{mirrored} -> {verdict}")
        return out


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.\-]", "-", text).lstrip(".-") or "x"


def cutout_id(seq_id: str, object_id: str) -> str:
    """``<seq_id>.<object_id>`` (characters unsafe in a file name replaced by ``-``)."""
    return f"{_safe(seq_id)}.{_safe(object_id)}"


def _box_size(track: Track | None, node: ObjectNode) -> tuple[float, float, float]:
    """Median box over the frames the object was seen (all its frames when never seen)."""
    if track is None or not len(track):
        extent = (node.gaussians.means.abs().amax(dim=0) * 2.0).tolist()
        return (float(extent[0]), float(extent[1]), float(extent[2]))
    rows = track.visible if track.visible.any() else np.ones(len(track), dtype=bool)
    size = np.median(np.asarray(track.size)[rows], axis=0)
    return (float(size[0]), float(size[1]), float(size[2]))


def _clean_rows(node: ObjectNode, size: tuple[float, float, float], cfg: CutoutConfig) -> tuple[torch.Tensor, float]:
    """``(keep [N] bool, inside share)``: opaque Gaussians inside the box grown by the margin."""
    gs = node.gaussians
    half = torch.tensor(size, dtype=gs.means.dtype, device=gs.means.device) / 2.0
    opaque = gs.opacities >= cfg.min_opacity
    inside = (gs.means.abs() <= half * (1.0 + cfg.box_margin)).all(dim=1)
    share = float((inside & opaque).sum()) / max(int(opaque.sum()), 1)
    return (opaque & inside).cpu(), share


def walked_arc_length(node: NonRigidNode, frame_indices: np.ndarray) -> np.ndarray:
    """``[T_h]`` metres the node walked (ground positions of its poses, frames where it is present) up to
    each of its deform frames, 0 at the first."""
    xy = node.refined_poses()[:, :2, 3].detach().cpu().double().numpy()  # [F, 2]
    present = node.present.detach().cpu().numpy()
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1) * (present[1:] & present[:-1])
    arc = np.concatenate([[0.0], np.cumsum(steps)])  # [F]
    pos = np.clip(np.searchsorted(frame_indices, node.deform_frames), 0, frame_indices.size - 1)
    out = arc[pos]
    return (out - out[0]).astype(np.float32)


def _language_caption(language: LanguageScene | None, object_id: str) -> AppearanceCaption | None:
    if language is None:
        return None
    for entry in language.nodes:
        if entry.object_id == object_id and entry.caption is not None:
            return entry.caption
    return None


def _describe(category: str, size: tuple[float, float, float], caption: AppearanceCaption | None,
              attributes: Mapping[str, str]) -> tuple[str, str, str, str, str] | None:
    """``(caption, subtype, colour, lower colour, source)`` from a language caption or the log's attributes;
    ``None`` when neither names the colour."""
    if caption is not None and caption.color != UNKNOWN:
        lower = caption.lower_color or ""
        return caption.text, caption.subtype, caption.color, "" if lower == UNKNOWN else lower, "language"
    color = attributes.get("upper_color" if category == "pedestrian" else "color", "")
    if not color:
        return None
    subtype = attributes.get("subtype") or subtype_from_size(category, size)
    if category == "pedestrian" and subtype == "pedestrian":
        subtype = subtype_from_size(category, size)
    lower = attributes.get("lower_color", "")
    text = caption_text(category, subtype, (color,), color, lower or None)
    return text, subtype, color, lower, "log"


@dataclass(frozen=True)
class _Cleaned:
    """A node's Gaussians after cleaning (and mirroring), with the numbers the filter looks at (``kept``:
    Gaussians left by the cleaning, before mirroring)."""

    gaussians: GaussianSet
    kept: int
    size: tuple[float, float, float]
    inside_share: float
    coverage: dict[str, float]
    mirrored: str

    @property
    def mean_coverage(self) -> float:
        return float(np.mean(list(self.coverage.values())))


def _cleaned(node: ObjectNode, track: Track | None, category: str, cfg: CutoutConfig) -> _Cleaned:
    size = _box_size(track, node)
    keep, share = _clean_rows(node, size, cfg)
    gaussians = node.gaussians.detach().to("cpu").index(keep)
    gaussians.features = None  # language latents belong to the source scene's autoencoder
    kept, mirrored = len(gaussians), ""
    if not isinstance(node, NonRigidNode):
        gaussians.extras.pop(OFFSETS, None)
        if category == "vehicle" and cfg.mirror_vehicles and len(gaussians):
            gaussians, mirrored = mirror_completed(gaussians, size)
    return _Cleaned(gaussians, kept, size, share, side_coverage(gaussians, size), mirrored)


def _rejection(visible: int, cleaned: _Cleaned, cfg: CutoutConfig) -> str:
    """Why the filter rejects a node (``""``: it does not)."""
    if visible < cfg.min_visible_frames:
        return f"seen in {visible} < {cfg.min_visible_frames} frames"
    if cleaned.kept < cfg.min_gaussians:
        return f"{cleaned.kept} < {cfg.min_gaussians} Gaussians after cleaning"
    if cleaned.inside_share < cfg.min_inside_share:
        return f"only {cleaned.inside_share:.0%} of its Gaussians inside its box"
    if cleaned.mean_coverage < cfg.min_coverage:
        return f"side coverage {cleaned.mean_coverage:.2f} < {cfg.min_coverage}"
    return ""


def _cutout(node: ObjectNode, cleaned: _Cleaned, obj: ObjectInfo, graph: SceneGraph, seq_id: str,
            language: LanguageScene | None, extra: Mapping[str, str]) -> Asset:
    deform: dict[str, np.ndarray] = {}
    if isinstance(node, NonRigidNode):
        deform = {"deform_frames": np.asarray(node.deform_frames, dtype=np.int64),
                  "deform_arc_length": walked_arc_length(node, graph.frame_indices)}
    attributes = {"node_id": str(node.node_id), **extra,
                  **{f"coverage_{side}": f"{value:.3f}" for side, value in cleaned.coverage.items()},
                  "coverage": f"{cleaned.mean_coverage:.3f}", **({"mirrored": cleaned.mirrored} if cleaned.mirrored
                                                               else {})}
    size = cleaned.size
    known = _describe(obj.category, size, _language_caption(language, obj.object_id), obj.attributes)
    subtype = known[1] if known else subtype_from_size(obj.category, size)
    asset = Asset(asset_id=cutout_id(seq_id, obj.object_id), category=obj.category, subtype=subtype,
                  caption=known[0] if known else subtype, color=known[2] if known else UNKNOWN, size=size,
                  source_seq=seq_id, source_object=obj.object_id, gaussians=cleaned.gaussians,
                  attributes={**attributes, **({LOWER_COLOR: known[3]} if known and known[3] else {})}, **deform)
    if known is not None:
        return replace(asset, attributes={**asset.attributes, "caption_source": known[4]})
    seen = describe_asset(asset)
    lower = {LOWER_COLOR: seen.lower_color} if seen.lower_color and seen.lower_color != UNKNOWN else {}
    return replace(asset, caption=seen.text, color=seen.color,
                   attributes={**asset.attributes, **lower, "caption_source": "render"})


def cutout_assets(graph: SceneGraph, objects: Sequence[ObjectInfo], tracks: Sequence[Track], *, seq_id: str,
                  language: LanguageScene | None = None, config: CutoutConfig = CutoutConfig(),
                  scene_hash: str = "") -> tuple[list[Asset], CutoutReport]:
    """Assets of the good-enough vehicle and pedestrian nodes of ``graph`` (see the module docstring).

    Args:
        graph: a reconstructed scene graph (any device).
        objects, tracks: the log's objects and tracks (matched to nodes by ``object_id``).
        seq_id: the source sequence (asset ids are ``<seq_id>.<object_id>``).
        language: the scene's language scene (captions), if aligned.
        config: the filter.
        scene_hash: recorded in each asset's ``attributes["source_scene"]``.
    Returns:
        ``(assets in node order, report)``.

    Raises:
        ValueError: ``config.categories`` names a category that cannot be cut out.
    """
    bad = [c for c in config.categories if c not in ("vehicle", "pedestrian")]
    if bad:
        raise ValueError(f"CutoutConfig.categories: {bad} cannot be cut out (vehicle and pedestrian nodes can)")
    info = {o.object_id: o for o in objects}
    track_of = {t.object_id: t for t in tracks}
    assets, decisions = [], []
    for node in graph.object_nodes:
        obj = info.get(node.object_id)
        if obj is None or obj.category not in config.categories:
            continue
        track = track_of.get(node.object_id)
        visible = int(np.count_nonzero(track.visible)) if track is not None else 0
        cleaned = _cleaned(node, track, obj.category, config)
        reason = _rejection(visible, cleaned, config)
        decisions.append(CutoutDecision(node.object_id, node.node_id, obj.category, not reason, reason, visible,
                                        (cleaned.kept, len(node.gaussians)), cleaned.inside_share,
                                        cleaned.mean_coverage, cleaned.mirrored))
        if reason:
            continue
        extra = {"visible_frames": str(visible), "source_scene": scene_hash,
                 "gaussians_total": str(len(node.gaussians))}
        assets.append(_cutout(node, cleaned, obj, graph, seq_id, language, extra))
    report = CutoutReport(seq_id, config, tuple(decisions))
    for line in report.lines():
        logger.info("%s", line)
    return assets, report


__all__ = ["CutoutConfig", "CutoutDecision", "CutoutReport", "cutout_assets", "cutout_id", "walked_arc_length"]
