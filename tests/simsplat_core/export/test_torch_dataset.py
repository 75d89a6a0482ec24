"""The agent-centric torch Dataset over the Parquet layout: samples, frames, masks, map, collation."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch
from torch.utils.data import DataLoader

from simsplat_core.export.agent_samples import EDIT_FLAGS, FUTURE_FEATURES, HISTORY_FEATURES, MAP_POINT_FEATURES
from simsplat_core.export.record import HEADING, SIGNAL_STATES, VX, VY, ExportScenario, X, Y
from simsplat_core.export.torch_dataset import (
    PADDED_KEYS,
    AgentCentricDataset,
    agent_to_world,
    collate_agent_samples,
)

from .conftest import make_scenario
from .parquet_fixtures import write_dataset

SPEED = 5.0
TURNED = 0.7  # heading of the predicted agent (radians)


def _turned_scenario(scenario_id: str, num_steps: int = 50) -> ExportScenario:
    """``make_scenario(4, num_steps)`` with its track to predict (row 1, id 8) driving straight at ``SPEED`` along
    ``TURNED`` from (12, -3), and its last track (id 10) appearing only after the current step."""
    s = make_scenario(num_agents=4, num_steps=num_steps, scenario_id=scenario_id)
    states, valid = s.states.copy(), s.valid.copy()
    t = s.timestamps_s
    direction = np.array([np.cos(TURNED), np.sin(TURNED)])
    states[1, :, [X, Y]] = (np.array([12.0, -3.0])[:, None] + SPEED * direction[:, None] * t)
    states[1, :, HEADING] = TURNED
    states[1, :, [VX, VY]] = SPEED * direction[:, None]
    valid[3, :12] = False
    states[3, :12] = 0.0
    return dataclasses.replace(s, states=states, valid=valid, objects_of_interest=(8, 10))


@pytest.fixture
def dataset_root(tmp_path):
    return write_dataset(tmp_path / "parquet", {
        ("train", "000"): [_turned_scenario("a"), _turned_scenario("b")],
        ("train", "001"): [_turned_scenario("c")],
        ("val", "000"): [make_scenario(num_agents=2, num_steps=30, scenario_id="v")],
    })


def test_samples_are_the_selected_agents_valid_at_the_current_step(dataset_root):
    assert len(AgentCentricDataset(dataset_root, "train")) == 3  # one track to predict each
    of_interest = AgentCentricDataset(dataset_root, "train", agents="of_interest")
    assert len(of_interest) == 3  # track 10 of interest but not yet there at the current step
    all_valid = AgentCentricDataset(dataset_root, "train", agents="all_valid")
    assert len(all_valid) == 3 * 3
    assert [(all_valid[i]["scenario_id"], int(all_valid[i]["track_id"])) for i in range(3)] == [
        ("a", 7), ("a", 8), ("a", 9)]
    assert len(AgentCentricDataset(dataset_root, "val", agents="all_valid")) == 2
    assert len(AgentCentricDataset(dataset_root, None, agents="all_valid")) == 3 * 3 + 2
    with pytest.raises(ValueError, match="agents must be"):
        AgentCentricDataset(dataset_root, "train", agents="every")  # type: ignore[arg-type]


def test_sample_shapes_and_types(dataset_root):
    sample = AgentCentricDataset(dataset_root, "train", history_steps=11, future_steps=80, points_per_polyline=20)[0]
    h, fu, p = 11, 80, 20
    assert sample["history"].shape == (h, len(HISTORY_FEATURES)) and sample["history"].dtype == torch.float32
    assert sample["history_valid"].shape == (h,) and sample["history_valid"].dtype == torch.bool
    assert sample["future"].shape == (fu, len(FUTURE_FEATURES)) and sample["future_valid"].shape == (fu,)
    m, n = len(sample["map_kind"]), len(sample["neighbor_type"])
    assert 0 < m <= 64 and 0 < n <= 32
    assert sample["map_polylines"].shape == (m, p, len(MAP_POINT_FEATURES)) and sample["map_valid"].shape == (m, p)
    assert sample["neighbors"].shape == (n, h, len(HISTORY_FEATURES)) and sample["neighbors_valid"].shape == (n, h)
    assert sample["edit_flags"].shape == (len(EDIT_FLAGS),)
    assert sample["origin"].shape == (4,) and sample["origin"].dtype == torch.float64
    assert sample["agent_type"].shape == () and sample["track_id"].shape == ()


def test_agent_frame_puts_the_agent_at_the_origin_heading_along_x(dataset_root):
    sample = AgentCentricDataset(dataset_root, "train")[0]
    now = sample["history"][-1]
    assert now[0].item() == pytest.approx(0, abs=1e-4) and now[1].item() == pytest.approx(0, abs=1e-4)
    assert (now[2].item(), now[3].item()) == pytest.approx((1.0, 0.0), abs=1e-6)  # cos, sin of the heading
    assert (now[4].item(), now[5].item()) == pytest.approx((SPEED, 0.0), abs=1e-4)  # velocity along +x
    k = torch.arange(1, 81, dtype=torch.float32)
    valid = sample["future_valid"]
    torch.testing.assert_close(sample["future"][valid, 0], SPEED * 0.1 * k[valid], atol=1e-3, rtol=0)
    torch.testing.assert_close(sample["future"][valid, 1], torch.zeros(int(valid.sum())), atol=1e-3, rtol=0)
    torch.testing.assert_close(sample["future"][valid, 2], torch.zeros(int(valid.sum())), atol=1e-5, rtol=0)
    current = 10
    start = np.array([12.0, -3.0]) + SPEED * current * 0.1 * np.array([np.cos(TURNED), np.sin(TURNED)])
    np.testing.assert_allclose(sample["origin"].numpy()[[0, 1, 3]], [*start, TURNED], atol=1e-5)
    world = agent_to_world(sample["future"][None, :3, :2], sample["origin"][None])[0]
    expected = start + SPEED * 0.1 * np.arange(1, 4)[:, None] * np.array([np.cos(TURNED), np.sin(TURNED)])
    np.testing.assert_allclose(world.numpy(), expected, atol=1e-3)


def test_neighbors_are_other_agents_in_the_agent_frame_nearest_first(dataset_root):
    sample = AgentCentricDataset(dataset_root, "train")[0]
    scene = _turned_scenario("a")
    c, s = np.cos(TURNED), np.sin(TURNED)
    rotation = np.array([[c, s], [-s, c]])
    ids = sample["neighbor_track_id"].tolist()
    assert ids and 8 not in ids
    for n, track_id in enumerate(ids):
        row = list(scene.track_ids).index(track_id)
        expected = rotation @ (scene.states[row, 10, :2] - sample["origin"].numpy()[:2])
        np.testing.assert_allclose(sample["neighbors"][n, -1, :2].numpy(), expected, atol=1e-4)
        heading = scene.states[row, 10, HEADING] - TURNED
        np.testing.assert_allclose(sample["neighbors"][n, -1, 2:4].numpy(), [np.cos(heading), np.sin(heading)],
                                   atol=1e-5)
    distances = sample["neighbors"][:, -1, :2].norm(dim=-1)
    assert torch.all(distances[1:] >= distances[:-1])


def test_validity_masks_cover_steps_outside_the_track_and_the_scenario(dataset_root):
    data = AgentCentricDataset(dataset_root, "train", history_steps=15, future_steps=80, agents="all_valid")
    sample = data[1]  # track 8 of scenario "a": 50 steps, current step 10
    assert sample["history_valid"].tolist() == [False] * 4 + [True] * 11  # before the first step
    assert not sample["history"][:4].any()
    assert sample["future_valid"].tolist() == [True] * 39 + [False] * 41  # past the last step (49)
    assert not sample["future"][39:].any()
    late = AgentCentricDataset(dataset_root, "train", agents="of_interest", future_steps=5)
    assert all(int(late[i]["track_id"]) == 8 for i in range(len(late)))
    neighbors = data[0]["neighbor_track_id"].tolist()
    assert 10 not in neighbors and 7 not in neighbors  # invalid now / the agent itself


def _segment_distance(points: np.ndarray, closed: bool) -> float:
    """Smallest ground-plane distance from (0, 0) to a polyline (reference, per segment)."""
    pts = np.vstack([points, points[:1]]) if closed and len(points) > 2 else points
    if len(pts) == 1:
        return float(np.hypot(*pts[0, :2]))
    a, b = pts[:-1, :2], pts[1:, :2]
    ab = b - a
    u = np.clip(np.einsum("ij,ij->i", -a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12), 0, 1)
    return float(np.min(np.linalg.norm(a + u[:, None] * ab, axis=1)))


def test_map_polylines_are_the_features_within_the_radius_only(dataset_root):
    radius = 15.0
    data = AgentCentricDataset(dataset_root, "train", map_radius_m=radius, agents="all_valid")
    scene = _turned_scenario("a")
    for i in range(3):
        sample = data[i]
        origin = sample["origin"].numpy()
        c, s = np.cos(origin[3]), np.sin(origin[3])
        rotation = np.array([[c, s], [-s, c]])
        expected = set()
        for feature in scene.map_features:
            local = (feature.points[:, :2] - origin[:2]) @ rotation.T
            closed = feature.kind in ("crosswalk", "speed_bump")
            if _segment_distance(local, closed) <= radius - 0.05:  # densified every metre: a miss is under 1 cm
                expected.add(feature.feature_id)
        got = set(sample["map_feature_id"].tolist())
        assert expected <= got, (i, expected, got)
        points = sample["map_polylines"][..., :2][sample["map_valid"]]
        assert torch.all(points.norm(dim=-1) <= radius + 1e-3)
        assert 600 not in got and 500 not in got  # the speed bump at x=80 and the stop sign at x=60
        lane = sample["map_polylines"][sample["map_feature_id"] == 101][0]
        assert lane[:, 5 + 0].eq(1).all()  # kind one-hot: lane
        go = SIGNAL_STATES.index("LANE_STATE_GO")
        assert sample["map_signal_state"][sample["map_feature_id"] == 101].item() == go
        assert set(sample["map_signal_state"][sample["map_feature_id"] != 101].tolist()) <= {-1}
    capped = AgentCentricDataset(dataset_root, "train", max_polylines=2)[0]
    assert len(capped["map_kind"]) == 2


def test_edit_flags_of_an_edited_track(dataset_root):
    sample = AgentCentricDataset(dataset_root, "train")[0]
    flags = dict(zip(EDIT_FLAGS, sample["edit_flags"].tolist()))
    assert flags == {"edited": 1.0, "inserted": 0.0, "refined": 0.0, "of_interest": 1.0, "to_predict": 1.0,
                     "scenario_edited": 1.0}


def test_collate_pads_variable_entries_and_masks_them(dataset_root):
    data = AgentCentricDataset(dataset_root, "train", map_radius_m=4.0, agents="all_valid")
    samples = [data[i] for i in range(3)]
    lengths = {"neighbors": [len(s["neighbor_type"]) for s in samples],
               "map": [len(s["map_kind"]) for s in samples]}
    assert len(set(lengths["map"])) > 1  # the agents see different numbers of features
    batch = collate_agent_samples(samples)
    assert batch["history"].shape == (3, 11, len(HISTORY_FEATURES))
    assert batch["scenario_id"] == ["a", "a", "a"] and batch["track_id"].tolist() == [7, 8, 9]
    for key in PADDED_KEYS:
        group = "map" if key.startswith("map") else "neighbors"
        assert batch[key].shape[:2] == (3, max(lengths[group])), key
    for b, sample in enumerate(samples):
        m, n = lengths["map"][b], lengths["neighbors"][b]
        assert batch["map_mask"][b].tolist() == [True] * m + [False] * (batch["map_mask"].shape[1] - m)
        assert batch["neighbors_mask"][b].tolist() == [True] * n + [False] * (batch["neighbors_mask"].shape[1] - n)
        torch.testing.assert_close(batch["map_polylines"][b, :m], sample["map_polylines"])
        assert not batch["map_valid"][b, m:].any() and (batch["map_kind"][b, m:] == -1).all()


def test_dataloader_batches_with_the_collate_function(dataset_root):
    data = AgentCentricDataset(dataset_root, "train", agents="all_valid", future_steps=30)
    loader = DataLoader(data, batch_size=5, shuffle=False, collate_fn=collate_agent_samples)
    batches = list(loader)
    assert [len(b["scenario_id"]) for b in batches] == [5, 4]
    for batch in batches:
        size = len(batch["scenario_id"])
        assert batch["future"].shape == (size, 30, len(FUTURE_FEATURES))
        assert batch["map_polylines"].shape[0] == size and batch["map_mask"].shape == batch["map_kind"].shape
        assert batch["origin"].shape == (size, 4)
    assert collate_agent_samples([data[0]])["history"].shape[0] == 1
    with pytest.raises(ValueError, match="empty batch"):
        collate_agent_samples([])
