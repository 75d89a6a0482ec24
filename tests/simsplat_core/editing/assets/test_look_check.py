"""Exposure matching of inserted objects: the gain ladder on crops, the exposure variant, and apply_edit
switching a too-dark "white" asset to the variant that reads white where it stands."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from simsplat_core.editing.apply import apply_edit
from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.colors import UPPER_BODY, exposed
from simsplat_core.editing.assets.look_check import (
    MIN_LOOK_PIXELS,
    box_corners,
    exposure_gain,
    look_frames,
    look_renders,
    node_crops,
)
from simsplat_core.editing.assets.record import EXPOSED_FROM, Asset
from simsplat_core.editing.commands import EditProgram
from simsplat_core.editing.delta import apply_delta
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.ops import node_factory
from simsplat_core.editing.renders import render_frames
from simsplat_core.language.appearance.captioner import describe_track
from simsplat_core.language.appearance.crops import ObjectCrop
from simsplat_core.scene import GaussianSet, SceneGraph

CAR = (4.4, 1.9, 1.5)
#: Insert a white sedan 6 m ahead in the ego lane (near enough to be captioned in the 96 x 64 test cameras).
PROGRAM = {"commands": [{"op": "insert", "asset": {"description": "a white sedan"},
                         "placement": {"relation": "in_lane", "distance_m": 6}}]}


def _crop(value: float, size: int = 24) -> ObjectCrop:
    """A flat neutral square of display value ``value``."""
    rgb = np.full((size, size, 3), value, np.float32)
    return ObjectCrop(rgb, np.ones((size, size), bool), "vehicle", np.asarray(CAR), 0, "front", "obj")


def _dim_white_car(value: float, asset_id: str = "unit.dimwhite", n: int = 400,
                   rgb: tuple[float, float, float] | None = None, color: str = "white") -> Asset:
    g = torch.Generator().manual_seed(3)
    means = (torch.rand((n, 3), generator=g) - 0.5) * torch.tensor(CAR)
    fill = torch.full((n, 3), value) if rgb is None else torch.tensor(rgb).expand(n, 3).clone()
    gs = GaussianSet.create(means, torch.full((n,), 0.2), fill, 0.95)
    return Asset(asset_id=asset_id, category="vehicle", subtype="sedan", caption=f"a {color} sedan",
                 color=color, size=CAR, source_seq="unit", source_object="car", gaussians=gs)


def test_a_grey_looking_object_asked_white_gets_a_brightening_gain():
    crops = [_crop(0.45)] * 3
    seen, gain = exposure_gain(crops, "white")
    assert seen != "white" and gain > 1.0
    brighter = [ObjectCrop(np.clip(c.rgb * gain, 0, 1), c.mask, c.category, c.box_size, 0, "front", "obj")
                for c in crops]
    assert describe_track(brighter).colors[0] == "white"


def test_an_object_asked_darker_gets_a_darkening_gain_and_one_that_reads_right_none():
    seen, gain = exposure_gain([_crop(0.62)] * 2, "silver")
    assert seen == "white" and gain < 1.0
    seen, gain = exposure_gain([_crop(0.95)] * 2, "white")
    assert (seen, gain) == ("white", 1.0)


def _flat(rgb: tuple[float, float, float]) -> ObjectCrop:
    return ObjectCrop(np.tile(np.array(rgb, np.float32), (20, 20, 1)), np.ones((20, 20), bool), "vehicle",
                      np.asarray(CAR), 0, "front", "obj")


def test_hues_are_checked_but_never_exposure_matched():
    red = _flat((0.7, 0.1, 0.1))
    assert exposure_gain([red], "blue") == ("red", 1.0)  # another hue: another asset's job
    assert exposure_gain([red], "white") == ("red", 1.0)
    assert exposure_gain([_flat((0.1, 0.1, 0.35))] * 2, "blue") == ("black", 1.0)


def test_the_exposure_variant_scales_colours_and_round_trips_through_the_bank():
    asset = _dim_white_car(0.4)
    bank = AssetBank.from_assets([asset])
    variant = bank.get("unit.dimwhite~exp1.50")
    assert variant.asset_id == "unit.dimwhite~exp1.50"
    assert variant.attributes[EXPOSED_FROM] == "unit.dimwhite"
    assert torch.allclose(variant.gaussians.rgb, asset.gaussians.rgb * 1.5, atol=1e-4)
    assert torch.equal(variant.gaussians.means, asset.gaussians.means)
    with pytest.raises(ValueError, match="exposure gain"):
        exposed(asset, 5.0)


def _clear_background(graph: SceneGraph) -> SceneGraph:
    """The graph with its (random-cloud) background made transparent, so inserted objects are seen."""
    bg = graph.nodes[0]
    clear = bg.gaussians.map_rows(lambda name, t: torch.full_like(t, -30.0) if name == "opacity_logits" else t)
    return dataclasses.replace(graph, nodes=(dataclasses.replace(bg, gaussians=clear), *graph.nodes[1:]))


def test_apply_edit_switches_a_dark_white_asset_to_a_variant_that_reads_white(edit_log, edit_graph, edit_language,
                                                                               engine):
    bank = AssetBank.from_assets([_dim_white_car(0.5)])
    ctx = EditContext.create(edit_log, _clear_background(edit_graph), edit_language, engine, bank)
    edited = apply_edit(ctx, EditProgram.model_validate(PROGRAM))
    added = edited.delta.added[0]
    assert added.asset_id.startswith("unit.dimwhite~exp")
    renders = list(render_frames(edited.graph, edit_log, look_frames(edited.states, added.object_id)))
    crops = node_crops(renders, added.node_id, added.object_id, "vehicle", CAR)
    assert crops and describe_track(crops).colors[0] == "white"
    rebuilt = apply_delta(ctx.graph, edited.delta, node_factory(bank.get, ctx.graph.frame_indices))
    assert torch.allclose(rebuilt.at(5.0).colors, edited.graph.at(5.0).colors)
    assert "exposure" in edited.outcomes[0].summary



def test_an_asset_no_gain_can_make_white_is_swapped_for_another(edit_log, edit_graph, edit_language, engine):
    # the grey one ranks first (more Gaussians break the caption tie) but reads grey even at the largest gain
    bank = AssetBank.from_assets([_dim_white_car(0.12, "unit.grey", n=500), _dim_white_car(0.85, "unit.white")])
    ctx = EditContext.create(edit_log, _clear_background(edit_graph), edit_language, engine, bank)
    assert bank.retrieve(EditProgram.model_validate(PROGRAM).commands[0].asset, engine.text_encoder).asset_id == \
        "unit.grey"
    edited = apply_edit(ctx, EditProgram.model_validate(PROGRAM))
    assert edited.delta.added[0].asset_id.split("~")[0] == "unit.white"


def test_a_blue_asset_that_reads_purple_here_is_swapped_for_one_that_reads_blue(edit_log, edit_graph,
                                                                                  edit_language, engine):
    """A hue gets no gain, but an asset captioned blue that renders as another colour where it is inserted is
    replaced by the next one that reads blue."""
    purple = _dim_white_car(0.0, "unit.purple", n=500, rgb=(0.45, 0.15, 0.6), color="blue")
    blue = _dim_white_car(0.0, "unit.blue", rgb=(0.1, 0.25, 0.8), color="blue")
    bank = AssetBank.from_assets([purple, blue])
    program = EditProgram.model_validate({"commands": [{**PROGRAM["commands"][0],
                                                        "asset": {"description": "a blue sedan"}}]})
    assert bank.retrieve(program.commands[0].asset, engine.text_encoder).asset_id == "unit.purple"
    ctx = EditContext.create(edit_log, _clear_background(edit_graph), edit_language, engine, bank)
    assert apply_edit(ctx, program).delta.added[0].asset_id == "unit.blue"


def test_look_renders_only_the_cameras_that_see_the_object(edit_log, edit_graph, edit_language, engine):
    bank = AssetBank.from_assets([_dim_white_car(0.85, "unit.white")])
    ctx = EditContext.create(edit_log, _clear_background(edit_graph), edit_language, engine, bank)
    edited = apply_edit(ctx, EditProgram.model_validate(PROGRAM))
    added = edited.delta.added[0]
    frames = look_frames(edited.states, added.object_id)
    some = look_renders(edited.graph, edit_log, edited.states, [added.object_id], frames)
    every = list(render_frames(edited.graph, edit_log, frames))
    assert 0 < sum(len(f.cameras) for f in some) < sum(len(f.cameras) for f in every)  # 6 m ahead: front cameras
    seen = {(f.frame_idx, c) for f in every for c, ids in zip(f.cameras, f.node_id)
            if (ids == added.node_id).sum() >= MIN_LOOK_PIXELS}
    assert seen <= {(f.frame_idx, c) for f in some for c in f.cameras}  # no view that could be captioned is skipped
    box = box_corners(edited.states, added.object_id, 0)
    assert box.shape == (8, 3) and np.allclose(box[:, :2].mean(axis=0), edited.states.xy[
        edited.states.index(added.object_id), 0])


PED = (0.8, 0.6, 1.75)
PED_PROGRAM = {"commands": [{"op": "insert", "asset": {"description": "a person in a white top"},
                             "placement": {"relation": "in_lane", "distance_m": 5}}]}


def _dim_white_top_pedestrian(value: float, n: int = 600) -> Asset:
    """A standing pedestrian: a top of grey ``value`` (caption: white) over blue trousers."""
    g = torch.Generator().manual_seed(5)
    means = (torch.rand((n, 3), generator=g) - 0.5) * torch.tensor(PED)
    upper = means[:, 2] > 0.0
    rgb = torch.where(upper.unsqueeze(1), torch.full((n, 3), value), torch.tensor([[0.1, 0.2, 0.6]]))
    gs = GaussianSet.create(means, torch.full((n,), 0.1), rgb, 0.95)
    return Asset(asset_id="unit.dimped", category="pedestrian", subtype="adult",
                 caption="a pedestrian in a white top and blue trousers", color="white", size=PED,
                 source_seq="unit", source_object="ped", gaussians=gs, attributes={"lower_color": "blue"})


def test_a_pedestrian_exposure_variant_scales_its_top_only():
    asset = _dim_white_top_pedestrian(0.4)
    variant = exposed(asset, 1.5)
    z = asset.gaussians.means[:, 2]
    top = (z >= -PED[2] / 2 + UPPER_BODY[0] * PED[2]) & (z <= -PED[2] / 2 + UPPER_BODY[1] * PED[2])
    assert torch.allclose(variant.gaussians.rgb[top], asset.gaussians.rgb[top] * 1.5, atol=1e-4)
    assert torch.allclose(variant.gaussians.rgb[~top], asset.gaussians.rgb[~top], atol=1e-5)


def test_apply_edit_exposure_matches_a_pedestrian_top_asked_white(edit_log, edit_graph, edit_language, engine):
    bank = AssetBank.from_assets([_dim_white_top_pedestrian(0.45)])
    ctx = EditContext.create(edit_log, _clear_background(edit_graph), edit_language, engine, bank)
    edited = apply_edit(ctx, EditProgram.model_validate(PED_PROGRAM))
    added = edited.delta.added[0]
    assert added.asset_id.startswith("unit.dimped~exp")
    renders = list(render_frames(edited.graph, edit_log, look_frames(edited.states, added.object_id)))
    crops = node_crops(renders, added.node_id, added.object_id, "pedestrian", PED)
    assert crops and describe_track(crops).upper_color == "white"
