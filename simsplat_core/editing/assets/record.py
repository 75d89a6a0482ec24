"""``Asset``: one insertable object of the asset bank -- canonical Gaussians plus what they are.

**Frame.** An asset's Gaussians live in the object's *box frame*, the frame reconstructed object nodes
use (``scene.nodes``): origin at the box centre, x along the heading, y to the left, z up. The ground
is therefore at ``z = -h / 2``; placing an asset with a box pose whose centre is ``h / 2`` above the
road (what ``scene.transforms.poses_from_boxes`` makes of a track) puts it on the road.

**Deformation.** A deformable asset (a pedestrian cut out of a reconstruction) keeps the non-rigid
node's per-Gaussian offsets ``gaussians.extras["offsets"] [N, T_h, 3]`` at its source deform frames
``deform_frames [T_h]`` and the distance the source walked up to each of them, ``deform_arc_length
[T_h]`` (metres, 0 at the first): ``editing.assets.nodes`` retimes the gait to a new path by arc length.

Everything is on the CPU in float32; sizes are float32-representable, so a bank round-trips through
Parquet bit for bit.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import torch

from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.nodes import OFFSETS

AssetCategoryName = Literal["vehicle", "pedestrian", "static"]
#: Asset categories (``AssetSpec.category``).
ASSET_CATEGORIES: tuple[str, ...] = ("vehicle", "pedestrian", "static")
#: Attribute keys with a meaning (others are free-form facts).
RECOLOURED_FROM = "recoloured_from"
RESIZED_FROM = "resized_from"
EXPOSED_FROM = "exposed_from"
PROCEDURAL = "procedural"
#: A box with no Gaussians (``editing.assets.boxes``: inserts into logs without images).
BOX_ONLY = "box_only"
LOWER_COLOR = "lower_color"
#: Characters allowed in a stored asset id (it names the file ``gaussians/<asset_id>.parquet``).
ASSET_ID_RX = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]*$")
#: Separator of a derived variant's id: ``<asset_id>~<colour>`` / ``<asset_id>~<l>x<w>x<h>``.
VARIANT_SEP = "~"


def f32(value: float) -> float:
    """``value`` rounded to the nearest float32 (what Parquet stores)."""
    return float(np.float32(value))


@dataclass(frozen=True, eq=False)
class Asset:
    """One asset (see the module docstring for the frame and the deformation).

    Attributes:
        asset_id: unique in its bank; a derived variant (recoloured / resized at retrieval) has
            ``<base id>~<colour>`` / ``<base id>~<l>x<w>x<h>`` appended.
        category: ``"vehicle"``, ``"pedestrian"`` or ``"static"``.
        subtype: e.g. ``"sedan"``, ``"adult"``, ``"traffic cone"``.
        caption: what it looks like, e.g. ``"a red sedan"`` (what retrieval embeds).
        color: main colour name (``color_names.COLOR_NAMES``; a pedestrian's upper-body colour).
        size: box ``(length, width, height)`` metres (float32 values).
        source_seq, source_object: where it was cut out (``""`` object for procedural assets).
        gaussians: ``N`` Gaussians in the box frame; ``extras["offsets"] [N, T_h, 3]`` when deformable.
        deform_frames: ``[T_h]`` int64 source frames of the offsets (``None`` when rigid).
        deform_arc_length: ``[T_h]`` float32 metres walked by the source up to each deform frame.
        attributes: free-form string facts (``lower_color``, ``recoloured_from``, ``procedural``,
            ``visible_frames``, ``source_scene`` ...).
    """

    asset_id: str
    category: str
    subtype: str
    caption: str
    color: str
    size: tuple[float, float, float]
    source_seq: str
    source_object: str
    gaussians: GaussianSet
    deform_frames: np.ndarray | None = None
    deform_arc_length: np.ndarray | None = None
    attributes: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = f"asset {self.asset_id!r}"
        base = self.asset_id.split(VARIANT_SEP, 1)[0]
        if not ASSET_ID_RX.match(base):
            raise ValueError(f"{where}: id must match {ASSET_ID_RX.pattern} (it names a file)")
        if self.category not in ASSET_CATEGORIES:
            raise ValueError(f"{where}: category must be one of {ASSET_CATEGORIES}, got {self.category!r}")
        size = tuple(f32(v) for v in np.asarray(self.size, dtype=np.float64).reshape(-1))
        if len(size) != 3 or min(size) <= 0:
            raise ValueError(f"{where}: size must be three positive metres (l, w, h), got {self.size}")
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "attributes", {str(k): str(v) for k, v in self.attributes.items()})
        gs = self.gaussians.detach().to("cpu", torch.float32)
        object.__setattr__(self, "gaussians", gs)
        offsets = gs.extras.get(OFFSETS)
        has_frames = self.deform_frames is not None
        if (offsets is None) != (not has_frames) or (self.deform_arc_length is None) != (not has_frames):
            raise ValueError(f"{where}: offsets, deform_frames and deform_arc_length come together")
        if has_frames and offsets is not None:
            frames = np.asarray(self.deform_frames, dtype=np.int64).reshape(-1)
            arc = np.asarray(self.deform_arc_length, dtype=np.float32).reshape(-1)
            if frames.size == 0 or np.any(np.diff(frames) <= 0):
                raise ValueError(f"{where}: deform_frames must be non-empty and strictly increasing")
            if arc.shape != frames.shape or np.any(np.diff(arc) < 0):
                raise ValueError(f"{where}: deform_arc_length must be [T_h={frames.size}] and non-decreasing")
            if tuple(offsets.shape) != (len(gs), frames.size, 3):
                raise ValueError(f"{where}: offsets must be [N={len(gs)}, T_h={frames.size}, 3], "
                                 f"got {list(offsets.shape)}")
            object.__setattr__(self, "deform_frames", frames)
            object.__setattr__(self, "deform_arc_length", arc)

    # ------------------------------------------------------------------ views
    @property
    def num_gaussians(self) -> int:
        return len(self.gaussians)

    @property
    def deformable(self) -> bool:
        """Whether the asset carries a per-frame deformation (a cut-out pedestrian)."""
        return self.deform_frames is not None

    @property
    def offsets(self) -> torch.Tensor | None:
        """``[N, T_h, 3]`` offsets in the box frame, or ``None``."""
        return self.gaussians.extras.get(OFFSETS)

    @property
    def walked_m(self) -> float:
        """Metres the source walked over its deform frames (0 for rigid assets)."""
        arc = self.deform_arc_length
        return 0.0 if arc is None else float(arc[-1] - arc[0])

    @property
    def half_diagonal(self) -> float:
        """Half the box diagonal (a node's ``scale``)."""
        return float(0.5 * np.linalg.norm(self.size))

    @property
    def procedural(self) -> bool:
        return PROCEDURAL in self.attributes

    @property
    def box_only(self) -> bool:
        """A box with no Gaussians (``editing.assets.boxes``): its colour is a word, its size any size."""
        return BOX_ONLY in self.attributes

    @property
    def base_id(self) -> str:
        """The stored asset this one derives from (itself unless it is a variant)."""
        return self.asset_id.split(VARIANT_SEP, 1)[0]

    @property
    def label(self) -> str:
        """Caption plus provenance, for people: ``"a yellow sedan (recoloured from synth-000000.veh_01)"``."""
        notes = []
        if RECOLOURED_FROM in self.attributes:
            notes.append(f"recoloured from {self.attributes[RECOLOURED_FROM]}")
        if RESIZED_FROM in self.attributes:
            notes.append(f"resized from {self.attributes[RESIZED_FROM]}")
        if EXPOSED_FROM in self.attributes:
            notes.append(f"exposure-matched from {self.attributes[EXPOSED_FROM]}")
        if not notes:
            notes.append("procedural" if self.procedural else f"from {self.source_seq} {self.source_object}")
        return f"{self.caption} ({'; '.join(notes)})"


__all__ = ["ASSET_CATEGORIES", "ASSET_ID_RX", "Asset", "AssetCategoryName", "EXPOSED_FROM", "LOWER_COLOR", "PROCEDURAL",
           "RECOLOURED_FROM", "RESIZED_FROM", "VARIANT_SEP", "f32"]
