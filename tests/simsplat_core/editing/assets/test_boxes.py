"""Box-only assets (inserts into logs without images): retrieval by kind, colour and size without Gaussians, and a
bank hash that every process builds alike."""

from __future__ import annotations

import pytest

from simsplat_core.editing.assets.bank import AssetBank, content_hash
from simsplat_core.editing.assets.boxes import box_asset_bank, box_assets, is_box_bank
from simsplat_core.editing.assets.record import RECOLOURED_FROM
from simsplat_core.editing.commands import AssetSpec
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.text import TextEncoder, default_text_encoder
from simsplat_core.world.palette import VEHICLE_KIND_BY_NAME


@pytest.fixture(scope="module")
def encoder() -> TextEncoder:
    return default_text_encoder()


def test_a_truck_is_a_box_of_the_truck_kind_in_the_asked_colour(encoder) -> None:
    truck = box_asset_bank().retrieve(AssetSpec(description="a red truck", category="vehicle"), encoder)
    assert truck.box_only and truck.num_gaussians == 0
    assert truck.subtype == "truck" and truck.size == pytest.approx(VEHICLE_KIND_BY_NAME["truck"].size, abs=1e-5)
    assert truck.color == "red" and "red" in truck.caption and truck.attributes[RECOLOURED_FROM] == "box.truck"
    assert box_asset_bank().get(truck.asset_id).caption == truck.caption  # the variant id rebuilds it


def test_any_size_is_a_box_of_that_size_and_unknown_kinds_are_refused(encoder) -> None:
    bank = box_asset_bank()
    long_bus = bank.retrieve(AssetSpec(description="a bus", category="vehicle", size_m=(15.0, 2.6, 3.2)), encoder)
    assert long_bus.subtype == "bus" and long_bus.size == pytest.approx((15.0, 2.6, 3.2))
    with pytest.raises(EditRefused, match="no asset fits"):
        bank.retrieve(AssetSpec(description="a tram", category="vehicle", subtype="tram"), encoder)


def test_the_box_bank_hash_is_its_contents() -> None:
    assert is_box_bank(content_hash(box_assets()))
    assert not is_box_bank(AssetBank.from_assets(box_assets()[:3]).bank_hash) and not is_box_bank("")
