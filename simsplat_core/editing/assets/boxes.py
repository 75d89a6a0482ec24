"""Box-only assets: insertable objects of a kind's nominal size with no Gaussians, for logs without images.

A log without camera images (a Waymo Open Motion or Argoverse 2 motion-forecasting scenario) has nothing to
render, so an object inserted into it needs only a box: its category, subtype and size (what placement, motion
planning, refinement, validation and the stored trajectories read). :func:`box_asset_bank` holds one box per
kind the synthetic world knows (``world.palette.VEHICLE_KINDS``, the procedural static kinds
``editing.assets.procedural.STATIC_KINDS``) plus an adult and a child pedestrian, each in its kind's first colour;
retrieval works as for any bank (``AssetBank.retrieve``): another colour is a variant with only its colour and
caption changed (``bank.color_variant``), another size a box of that size (``bank.resized_variant``).

    bank = box_asset_bank()
    truck = bank.retrieve(AssetSpec(description="a stopped truck", category="vehicle"), encoder)
    truck.size, truck.num_gaussians            # (7.6, 2.45, 3.3), 0

The bank is built from constants only, so its content hash (``bank.content_hash``) is the same in every process:
a stored edit names it, and rebuilding the edit builds the same bank again (:func:`is_box_bank`).
"""

from __future__ import annotations

from functools import lru_cache

from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.procedural import STATIC_KINDS
from simsplat_core.editing.assets.record import BOX_ONLY, Asset
from simsplat_core.language.appearance.captioner import caption_text
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.world.palette import VEHICLE_KINDS

#: Pedestrian boxes ``(length, width, height)`` metres by subtype, and the colour of their top.
PEDESTRIAN_BOXES: dict[str, tuple[float, float, float]] = {"adult": (0.6, 0.6, 1.75), "child": (0.45, 0.45, 1.2)}
PEDESTRIAN_COLOR = "gray"


def box_asset(category: str, subtype: str, size: tuple[float, float, float], color: str) -> Asset:
    """A box-only asset (no Gaussians) of ``category`` / ``subtype`` at ``size`` metres in ``color``; its id is
    ``box.<subtype with dashes>``.

    Raises:
        ValueError: an unknown category or a non-positive size (``Asset``'s checks).
    """
    if category == "pedestrian":
        caption = caption_text("pedestrian", subtype, (), color, None)
    else:
        caption = caption_text(category, subtype, (color,))
    return Asset(asset_id=f"box.{subtype.replace(' ', '-')}", category=category, subtype=subtype, caption=caption,
                 color=color, size=size, source_seq="", source_object="", gaussians=GaussianSet.empty(),
                 attributes={BOX_ONLY: "1"})


def box_assets() -> list[Asset]:
    """One box per vehicle kind, pedestrian subtype and procedural static kind (module docstring)."""
    vehicles = [box_asset("vehicle", k.subtype, k.size, k.colors[0]) for k in VEHICLE_KINDS]
    pedestrians = [box_asset("pedestrian", s, size, PEDESTRIAN_COLOR) for s, size in PEDESTRIAN_BOXES.items()]
    statics = [box_asset("static", k.subtype, k.size, k.colors[0]) for k in STATIC_KINDS.values()]
    return [*vehicles, *pedestrians, *statics]


@lru_cache(maxsize=1)
def box_asset_bank() -> AssetBank:
    """The bank of :func:`box_assets` (one instance per process: its caption embeddings are cached on it)."""
    return AssetBank.from_assets(box_assets())


def is_box_bank(bank_hash: str) -> bool:
    """Whether ``bank_hash`` names :func:`box_asset_bank` (as a stored edit's delta records it)."""
    return bank_hash == box_asset_bank().bank_hash


__all__ = ["PEDESTRIAN_BOXES", "box_asset", "box_asset_bank", "box_assets", "is_box_bank"]
