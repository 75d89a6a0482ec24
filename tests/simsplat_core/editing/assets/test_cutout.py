"""Cut-outs from a small hand-built scene graph: the filter, cleaning, mirroring, captions, pedestrian gait."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from simsplat_core.color_names import DISPLAY_RGB
from simsplat_core.editing.assets.cutout import CutoutConfig, CutoutReport, cutout_assets
from simsplat_core.editing.assets.procedural import mesh_gaussians
from simsplat_core.editing.assets.quality import side_coverage
from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.scene import NonRigidNode, RigidNode, SceneGraph
from simsplat_core.scene.gaussians import GaussianSet
from simsplat_core.scene.nodes import OFFSETS, ObjectNode
from simsplat_core.scene.transforms import poses_from_boxes
from simsplat_core.types import ObjectInfo, Track
from simsplat_core.world.mesh import pedestrian_mesh
from tests.simsplat_core.editing.assets.fixtures import mesh_vehicle

FRAMES = np.arange(12)
PED_STEP = 0.15  # metres per frame


def _track(object_id: str, size, step: float = 0.0, seen: int = 12, y: float = 0.0) -> Track:
    n = FRAMES.size
    center = np.stack([np.arange(n) * step, np.full(n, y), np.full(n, size[2] / 2)], axis=1)
    visible = np.zeros(n, dtype=bool)
    visible[:seen] = True
    return Track(object_id, FRAMES.copy(), center, np.tile(np.asarray(size, float), (n, 1)), np.zeros(n),
                 np.full(n, step * 10), visible)


def _poses(track: Track) -> dict:
    poses = torch.as_tensor(poses_from_boxes(track.center, track.heading), dtype=torch.float32)
    return {"poses": poses, "present": torch.ones(FRAMES.size, dtype=torch.bool)}


def _pedestrian_gaussians(n_frames: int) -> GaussianSet:
    mesh = pedestrian_mesh(1.75, 0.0, 0.4, DISPLAY_RGB["red"], DISPLAY_RGB["blue"], (0.8, 0.6, 0.5), (0.1, 0.1, 0.1))
    gs = mesh_gaussians(mesh, 0.03, z_offset=-0.875)
    swing = torch.sin(torch.arange(n_frames) * 0.5)[None, :, None] * gs.means[:, None, 2:3].clamp(max=0) * 0.3
    gs.extras[OFFSETS] = swing.expand(len(gs), n_frames, 3).contiguous()
    return gs


@pytest.fixture(scope="module")
def scene() -> tuple[SceneGraph, list[ObjectInfo], list[Track], LanguageScene]:
    sedan = mesh_vehicle("x.sedan", "sedan", "red")
    floater = GaussianSet.create(torch.tensor([[9.0, 0.0, 0.0]]), torch.full((1,), 0.3), torch.ones(1, 3), 0.9)
    suv = mesh_vehicle("x.suv", "SUV", "blue")
    left_half = suv.gaussians.index(suv.gaussians.means[:, 1] > 0.05)  # seen from its left only
    hatch = mesh_vehicle("x.hatch", "hatchback", "green")
    tracks = [_track("veh_a", sedan.size), _track("veh_b", suv.size), _track("veh_c", sedan.size, seen=2),
              _track("veh_d", hatch.size), _track("ped_a", (0.8, 0.6, 1.75), step=PED_STEP, y=5.0),
              _track("ped_b", (0.8, 0.6, 1.75)), _track("cone", (0.4, 0.4, 0.7))]
    by_id = {t.object_id: t for t in tracks}
    ped_few = GaussianSet.create(torch.zeros(50, 3), torch.full((50,), 0.05), torch.ones(50, 3), 0.9)
    ped_few.extras[OFFSETS] = torch.zeros(50, FRAMES.size, 3)

    def rigid(node_id: int, oid: str, gs: GaussianSet, category: str = "vehicle") -> ObjectNode:
        return RigidNode(node_id, gs, object_id=oid, category=category, static=category == "static",
                         **_poses(by_id[oid]))

    def walker(node_id: int, oid: str, gs: GaussianSet) -> ObjectNode:
        return NonRigidNode(node_id, gs, object_id=oid, category="pedestrian", deform_frames=FRAMES.copy(),
                            **_poses(by_id[oid]))

    nodes = [rigid(1, "veh_a", GaussianSet.cat([sedan.gaussians, floater])), rigid(2, "veh_b", left_half),
             rigid(3, "veh_c", sedan.gaussians), rigid(4, "veh_d", hatch.gaussians),
             walker(5, "ped_a", _pedestrian_gaussians(FRAMES.size)), walker(6, "ped_b", ped_few),
             rigid(7, "cone", ped_few.index(torch.arange(10)).map_rows(lambda n, t: t[:, :1] if n == OFFSETS else t),
                   "static")]
    objects = [ObjectInfo("veh_a", "vehicle", "rigid", 1, attributes={"subtype": "sedan", "color": "red"}),
               ObjectInfo("veh_b", "vehicle", "rigid", 2), ObjectInfo("veh_c", "vehicle", "rigid", 3),
               ObjectInfo("veh_d", "vehicle", "rigid", 4),
               ObjectInfo("ped_a", "pedestrian", "nonrigid", 5,
                          attributes={"subtype": "pedestrian", "upper_color": "red", "lower_color": "blue"}),
               ObjectInfo("ped_b", "pedestrian", "nonrigid", 6), ObjectInfo("cone", "static", "static", 7)]
    caption = AppearanceCaption("a blue SUV", "vehicle", "SUV", ("blue",), confidence=0.9)
    language = LanguageScene("x", "", (NodeLanguage(2, "veh_b", "vehicle", "vehicle", None, caption, None),),
                             FRAMES, (), None, "e5")
    return SceneGraph(FRAMES, nodes), objects, tracks, language


@pytest.fixture(scope="module")
def cut(scene) -> tuple[list, CutoutReport]:
    graph, objects, tracks, language = scene
    return cutout_assets(graph, objects, tracks, seq_id="x", language=language, scene_hash="ab" * 8)


def test_the_filter_keeps_good_nodes_and_says_why_it_drops_the_others(cut) -> None:
    assets, report = cut
    assert [a.asset_id for a in assets] == ["x.veh_a", "x.veh_b", "x.veh_d", "x.ped_a"]
    reasons = {d.object_id: d.reason for d in report.rejected}
    assert reasons["veh_c"] == "seen in 2 < 8 frames"
    assert reasons["ped_b"].startswith("50 < 200 Gaussians")
    assert "cone" not in {d.object_id for d in report.decisions}  # static nodes are not cut out
    lines = report.lines()
    assert lines[0].startswith("x: kept 4 of 6 vehicle/pedestrian nodes") and any("veh_c" in ln for ln in lines)
    assert all(a.attributes["source_scene"] == "ab" * 8 for a in assets)


def test_cleaning_drops_floaters_and_features(scene, cut) -> None:
    graph = scene[0]
    assets, report = cut
    sedan = next(a for a in assets if a.source_object == "veh_a")
    assert sedan.num_gaussians == len(graph.node(1).gaussians) - 1  # the floater 9 m away is gone
    assert np.abs(sedan.gaussians.means.numpy()).max(axis=0)[0] < sedan.size[0] / 2 + 0.1
    assert sedan.gaussians.features is None
    decision = next(d for d in report.decisions if d.object_id == "veh_a")
    assert decision.gaussians == (sedan.num_gaussians, sedan.num_gaussians + 1)


def test_a_vehicle_seen_from_one_flank_is_mirrored(scene, cut) -> None:
    graph = scene[0]
    assets, _ = cut
    suv = next(a for a in assets if a.source_object == "veh_b")
    assert suv.attributes["mirrored"] == "left->right"
    before = side_coverage(graph.node(2).gaussians, suv.size)
    after = side_coverage(suv.gaussians, suv.size)
    assert before["right"] < 0.3 < before["left"] and after["right"] == pytest.approx(after["left"])
    assert suv.num_gaussians == 2 * len(graph.node(2).gaussians)
    assert float(suv.attributes["coverage"]) > float(np.mean(list(before.values())))
    sedan = next(a for a in assets if a.source_object == "veh_a")
    assert "mirrored" not in sedan.attributes  # both flanks were there


def test_captions_come_from_language_then_log_then_renders(cut) -> None:
    by_object = {a.source_object: a for a in cut[0]}
    assert (by_object["veh_b"].caption, by_object["veh_b"].attributes["caption_source"]) == ("a blue SUV", "language")
    assert (by_object["veh_a"].caption, by_object["veh_a"].attributes["caption_source"]) == ("a red sedan", "log")
    hatch = by_object["veh_d"]
    assert hatch.attributes["caption_source"] == "render"
    assert hatch.color == "green" and hatch.subtype == "hatchback" and hatch.caption == "a green hatchback"
    ped = by_object["ped_a"]
    assert ped.caption == "a pedestrian in a red top and blue trousers" and ped.subtype == "adult"
    assert ped.attributes["lower_color"] == "blue"


def test_pedestrians_keep_their_deformation_and_walked_distance(scene, cut) -> None:
    ped = next(a for a in cut[0] if a.source_object == "ped_a")
    node = scene[0].node(5)
    assert isinstance(node, NonRigidNode) and ped.deformable
    np.testing.assert_array_equal(ped.deform_frames, FRAMES)
    np.testing.assert_allclose(ped.deform_arc_length, PED_STEP * FRAMES, atol=1e-5)
    assert ped.offsets is not None and ped.offsets.shape == (ped.num_gaussians, FRAMES.size, 3)
    assert float(ped.offsets.abs().max()) > 0.05  # the limb motion came along


def test_only_vehicles_and_pedestrians_can_be_cut_out(scene) -> None:
    graph, objects, tracks, _ = scene
    with pytest.raises(ValueError, match="cannot be cut out"):
        cutout_assets(graph, objects, tracks, seq_id="x", config=CutoutConfig(categories=("static",)))
