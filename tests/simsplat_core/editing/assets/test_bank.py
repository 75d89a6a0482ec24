"""Asset retrieval: category / subtype / colour / size constraints, recolouring, refusals that list the bank."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from simsplat_core.editing.assets.bank import AssetBank, asked_top_color, wanted_from_spec
from simsplat_core.editing.assets.colors import body_rows
from simsplat_core.editing.assets.procedural import procedural_asset
from simsplat_core.editing.assets.record import RECOLOURED_FROM
from simsplat_core.editing.commands import AssetSpec
from simsplat_core.editing.result import EditRefused
from simsplat_core.language.appearance.colors import name_lab, rgb_to_lab
from simsplat_core.language.text import TextEncoder, default_text_encoder
from tests.simsplat_core.editing.assets.fixtures import mesh_vehicle, walking_pedestrian


@pytest.fixture(scope="module")
def encoder() -> TextEncoder:
    return default_text_encoder()


@pytest.fixture(scope="module")
def bank() -> AssetBank:
    return AssetBank.from_assets([
        mesh_vehicle("t.red-sedan", "sedan", "red"),
        mesh_vehicle("t.white-van", "van", "white"),
        mesh_vehicle("t.blue-suv", "SUV", "blue"),
        mesh_vehicle("t.black-suv", "SUV", "black"),
        walking_pedestrian(asset_id="t.ped-red"),
        procedural_asset("traffic cone", "orange"),
        procedural_asset("barrier", "white"),
        procedural_asset("jersey barrier", "gray"),
    ])


def _spec(description: str, **kw) -> AssetSpec:
    return AssetSpec(description=description, **kw)


@pytest.mark.parametrize(("description", "kw", "expected"), [
    ("a white van", {}, "t.white-van"),
    ("a red car", {"category": "vehicle"}, "t.red-sedan"),
    ("an SUV", {"color": "black"}, "t.black-suv"),
    ("a blue sport utility vehicle", {}, "t.blue-suv"),
    ("a pedestrian in a red coat", {}, "t.ped-red"),
    ("someone in blue trousers", {}, "t.ped-red"),  # the lower colour counts for pedestrians
    ("a row of orange cones", {"count": 4}, "proc.traffic-cone.orange"),
    ("a concrete barricade", {"color": "grey"}, "proc.jersey-barrier.gray"),
])
def test_retrieval_respects_category_subtype_and_colour(bank, encoder, description, kw, expected) -> None:
    assert bank.retrieve(_spec(description, **kw), encoder).asset_id == expected


def test_a_missing_colour_is_made_by_recolouring_the_body(bank, encoder) -> None:
    taxi = bank.retrieve(_spec("a yellow taxi"), encoder)
    assert taxi.asset_id.endswith("~yellow") and taxi.color == "yellow" and "yellow" in taxi.caption
    source = bank.get(taxi.attributes[RECOLOURED_FROM])
    assert source.category == "vehicle" and source.subtype in ("sedan", "SUV")
    assert "recoloured from" in taxi.label
    body = body_rows(source)
    new_rgb, old_rgb = taxi.gaussians.rgb.numpy(), source.gaussians.rgb.numpy()
    assert name_lab(np.median(rgb_to_lab(new_rgb[body]), axis=0)).name == "yellow"
    assert name_lab(np.median(rgb_to_lab(old_rgb[body]), axis=0)).name == source.color
    np.testing.assert_array_equal(new_rgb[~body], old_rgb[~body])  # glass, tyres and lights untouched
    assert body.mean() > 0.3 and (~body).sum() > 100
    assert bank.get(taxi.asset_id).asset_id == taxi.asset_id  # variants are reproducible by id


def test_recolouring_a_pedestrian_changes_the_top_only(bank, encoder) -> None:
    person = bank.retrieve(_spec("a pedestrian in a green jacket"), encoder)
    assert person.color == "green" and person.caption == "a pedestrian in a green top and blue trousers"
    assert person.offsets is not None and person.deform_frames is not None  # the gait stays


def test_procedural_assets_are_rebuilt_at_the_requested_size_and_colour(bank, encoder) -> None:
    cone = bank.retrieve(_spec("a tall green cone", size_m=(0.5, 0.5, 1.2)), encoder)
    assert cone.subtype == "traffic cone" and cone.color == "green" and cone.size == pytest.approx((0.5, 0.5, 1.2))
    means = cone.gaussians.means.numpy()
    assert means[:, 2].min() == pytest.approx(-0.6, abs=0.02) and means[:, 2].max() == pytest.approx(0.6, abs=0.02)


def test_sizes_far_from_every_asset_are_refused(bank, encoder) -> None:
    assert bank.retrieve(_spec("a sedan", size_m=(4.5, 1.8, 1.5)), encoder).asset_id == "t.red-sedan"
    with pytest.raises(EditRefused) as refused:
        bank.retrieve(_spec("a long vehicle", category="vehicle", size_m=(12.0, 2.5, 3.2)), encoder)
    assert refused.value.reason == "no_asset"
    assert "12 x 2.5 x 3.2" in str(refused.value) and "sedan (red; ~4.6 x 1.8 x 1.5 m)" in str(refused.value)


def test_refusal_says_what_was_asked_and_lists_the_category(bank, encoder) -> None:
    with pytest.raises(EditRefused) as refused:
        bank.retrieve(_spec("a purple bus"), encoder)
    message = str(refused.value)
    assert refused.value.reason == "no_asset"
    assert "'a purple bus'" in message and "subtype bus" in message and "colour purple" in message
    for listed in ("SUV (black, blue", "sedan (red", "van (white"):
        assert listed in message
    assert "traffic cone" not in message  # only the asked category is listed


@pytest.mark.parametrize(("description", "kw", "words"), [
    ("a cyclist", {}, ["no cyclist assets"]),
    ("a chartreuse car", {"color": "chartreuse"}, ["unknown colour 'chartreuse'", "yellow"]),
    ("a limousine", {"category": "vehicle", "subtype": "limousine"}, ["subtype limousine", "SUV"]),
])
def test_things_the_bank_cannot_give_are_refused(bank, encoder, description, kw, words) -> None:
    with pytest.raises(EditRefused) as refused:
        bank.retrieve(_spec(description, **kw), encoder)
    assert refused.value.reason == "no_asset"
    for word in words:
        assert word in str(refused.value)


def test_asset_id_picks_an_asset_or_names_the_missing_one(bank, encoder) -> None:
    assert bank.retrieve(_spec("anything", asset_id="t.white-van"), encoder).asset_id == "t.white-van"
    assert bank.get("t.white-van~red").color == "red"
    with pytest.raises(EditRefused, match="no asset 't.nothing'"):
        bank.get("t.nothing")


def test_the_spec_is_completed_from_its_words() -> None:
    wanted = wanted_from_spec(_spec("a row of orange cones by the kerb"))
    assert (wanted.category, wanted.subtype, wanted.color) == ("static", "traffic cone", "orange")
    wanted = wanted_from_spec(_spec("a grey taxi"))
    assert (wanted.category, wanted.subtype, wanted.color) == ("vehicle", "car", "gray")
    wanted = wanted_from_spec(_spec("a man", category="pedestrian"))
    assert (wanted.category, wanted.subtype) == ("pedestrian", None)


class CountingEncoder:
    """Counts the passages it embeds."""

    def __init__(self, inner: TextEncoder) -> None:
        self.inner, self.name, self.dim = inner, inner.name, inner.dim
        self.passages = 0

    def encode_queries(self, texts):
        return self.inner.encode_queries(texts)

    def encode_passages(self, texts):
        self.passages += len(texts)
        return self.inner.encode_passages(texts)


def test_caption_embeddings_are_computed_once(encoder) -> None:
    bank = AssetBank.from_assets([mesh_vehicle("t.a"), mesh_vehicle("t.b", "van", "white")])
    counting = CountingEncoder(encoder)
    bank.retrieve(_spec("a red car"), counting)
    bank.retrieve(_spec("a white van"), counting)
    assert counting.passages == 2


def test_banks_reject_duplicate_ids_and_bad_hashes() -> None:
    with pytest.raises(ValueError, match="duplicate asset ids"):
        AssetBank.from_assets([mesh_vehicle("t.a"), mesh_vehicle("t.a")])
    with pytest.raises(ValueError, match="hex"):
        AssetBank((mesh_vehicle("t.a"),), "not-a-hash")


def test_asset_modules_are_framework_free() -> None:
    code = (
        "import sys, simsplat_core.editing.assets.bank, simsplat_core.editing.assets.cutout, "
        "simsplat_core.editing.assets.nodes, simsplat_core.viz.asset_sheet; "
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('prefect', 'ray', 'storage', 'tasks', 'flows', "
        "'pyarrow')); assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_pedestrian_top_colour_is_not_taken_from_trousers(encoder) -> None:
    # grey top over black trousers vs black top over blue trousers: "a black shirt" is the second one's top
    grey = replace(walking_pedestrian(asset_id="t.ped-grey"), color="gray",
                   caption="a pedestrian in a gray top and black trousers", attributes={"lower_color": "black"})
    black = replace(walking_pedestrian(asset_id="t.ped-black"), color="black",
                    caption="a pedestrian in a black top and blue trousers", attributes={"lower_color": "blue"})
    bank = AssetBank.from_assets([grey, black])
    for description in ("a person wearing a black shirt", "a pedestrian in a black hoodie"):
        assert bank.retrieve(_spec(description, category="pedestrian", color="black"), encoder).asset_id == \
            "t.ped-black"
    assert bank.retrieve(_spec("someone in black trousers", color="black"), encoder).asset_id == "t.ped-grey"
    assert asked_top_color(_spec("someone in black trousers", color="black")) is None
    assert asked_top_color(_spec("a person in a black top and black jeans", color="black")) == "black"
    # both garments named: the asset wearing both wins over one with the top only
    brown = replace(walking_pedestrian(asset_id="t.ped-blue-brown"), color="blue",
                    caption="a pedestrian in a blue top and brown trousers", attributes={"lower_color": "brown"})
    blue = replace(walking_pedestrian(asset_id="t.ped-blue-gray", n=12), color="blue",
                   caption="a pedestrian in a blue top and gray trousers", attributes={"lower_color": "gray"})
    bank = AssetBank.from_assets([brown, blue])
    assert bank.retrieve(_spec("a person in a blue top and brown jeans", color="blue"), encoder).asset_id == \
        "t.ped-blue-brown"
