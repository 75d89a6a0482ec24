"""Scene graphs by value: pure node removal / insertion / pose replacement, poses at any time."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from simsplat_core.scene import (
    Extrapolation,
    NonRigidNode,
    ObjectNode,
    OffsetExtrapolation,
    PoseTrack,
    RigidNode,
    SceneGraph,
)
from simsplat_core.scene.transforms import poses_from_boxes

from .graphs import N_FRAMES, camera, gaussians, make_graph, rigid_track


def _snapshot(graph: SceneGraph) -> dict:
    """Every tensor value, id and the metadata of a graph (deep copies)."""
    out = {"ids": [n.node_id for n in graph.nodes], "metadata": dict(graph.metadata), "revision": graph.revision}
    for n in graph.nodes:
        for name, t in n.tensors().items():
            out[(n.node_id, name)] = t.detach().clone()
        if isinstance(n, ObjectNode):
            out[(n.node_id, "poses")] = n.poses.clone()
            out[(n.node_id, "present")] = n.present.clone()
    return out


def _assert_unchanged(graph: SceneGraph, before: dict) -> None:
    after = _snapshot(graph)
    assert after.keys() == before.keys()
    for key, value in before.items():
        if isinstance(value, torch.Tensor):
            assert torch.equal(after[key], value), key
        else:
            assert after[key] == value, key


def _box(x: float, y: float, n: int = N_FRAMES, heading: float = 0.0) -> np.ndarray:
    center = np.tile([[x, y, 0.8]], (n, 1))
    return poses_from_boxes(center, np.full(n, heading)).astype(np.float32)


def _new_car(node_id: int = 0) -> RigidNode:
    return RigidNode(node_id, gaussians([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]], (0.1, 0.1, 0.9), seed=9),
                     object_id="inserted", category="vehicle", scale=2.0)


def test_without_drops_nodes_and_leaves_the_original() -> None:
    graph = make_graph()
    before = _snapshot(graph)
    edited = graph.without([1, 3])
    assert [n.node_id for n in edited.nodes] == [0, 2]
    assert edited.at(2).included_nodes == (0, 2)
    assert edited.num_gaussians == graph.num_gaussians - len(graph.node(1).gaussians) - len(graph.node(3).gaussians)
    assert edited.node(2) is graph.node(2)  # unchanged nodes are shared, not copied
    assert edited.revision and edited.revision != graph.revision
    _assert_unchanged(graph, before)
    assert graph.at(2).included_nodes == (0, 1, 2, 3)


@pytest.mark.parametrize("call", [
    lambda g: g.without([7]),
    lambda g: g.with_poses(7, _box(0, 0)),
])
def test_unknown_ids_raise_naming_the_id(call) -> None:
    with pytest.raises(ValueError, match="no node 7"):
        call(make_graph())


def test_with_node_on_the_frame_axis_assigns_the_next_id() -> None:
    graph = make_graph()
    before = _snapshot(graph)
    edited = graph.with_node(_new_car(), torch.as_tensor(_box(10.0, 1.0)))
    assert [n.node_id for n in edited.nodes] == [0, 1, 2, 3, 4]
    node = edited.node(4)
    assert node.object_id == "inserted" and node.track is None
    composed = edited.at(2)
    assert 4 in composed.included_nodes
    rows = composed.node_mask(4)
    torch.testing.assert_close(composed.means[rows][0], torch.tensor([10.0, 1.0, 0.8]), atol=1e-5, rtol=0)
    # the other nodes compose exactly as before
    old = graph.at(2)
    for nid in (0, 1, 2, 3):
        torch.testing.assert_close(composed.means[composed.node_mask(nid)], old.means[old.node_mask(nid)])
    _assert_unchanged(graph, before)
    with pytest.raises(ValueError, match="node id 2 is taken"):
        graph.with_node(_new_car(2), torch.as_tensor(_box(0, 0)))
    with pytest.raises(ValueError, match=r"\[F=5, 4, 4\]"):
        graph.with_node(_new_car(), torch.as_tensor(_box(0, 0, n=3)))


def test_with_node_renders_the_inserted_object() -> None:
    graph = make_graph().without([1, 2, 3])
    c2w, K = camera()
    with torch.no_grad():
        empty = graph.render(2, c2w, K, 64, 48)
        edited = graph.with_node(_new_car(), torch.as_tensor(_box(6.0, 0.0)))
        shown = edited.render(2, c2w, K, 64, 48)
    new_id = edited.nodes[-1].node_id
    assert new_id == 1  # the next free id after the background
    assert not bool((empty.node_id == new_id).any())
    assert int((shown.node_id == new_id).sum()) > 10


def test_a_supplied_track_runs_past_the_last_frame() -> None:
    graph = make_graph()
    before = _snapshot(graph)
    times = np.array([0.0, 2.5, 10.0])
    track = PoseTrack(times, torch.as_tensor(np.stack([_box(x, 0.0, n=1)[0] for x in (4.0, 9.0, 24.0)])))
    edited = graph.with_node(_new_car(), track)
    node = edited.node(4)
    assert node.track is not None and torch.equal(node.track.poses, track.poses)
    # on the frame axis the node's poses are the track's samples (records, training, renders)
    torch.testing.assert_close(node.poses[:, 0, 3], torch.tensor([4.0, 6.0, 8.0, 9.0 + 15.0 * 0.5 / 7.5,
                                                                   9.0 + 15.0 * 1.5 / 7.5]))
    for t, x in [(1.25, 6.5), (2.5, 9.0), (7.0, 9.0 + 15.0 * 4.5 / 7.5), (10.0, 24.0), (12.0, 24.0)]:
        objs, poses, alive = edited.object_poses_at(t)
        k = [n.node_id for n in objs].index(4)
        assert bool(alive[k]) and float(poses[k, 0, 3]) == pytest.approx(x, abs=1e-5), t
    # past the log's frames: log nodes hold their last frame, the car (absent there) stays absent
    late = edited.at(8.0)
    assert late.included_nodes == (0, 2, 3, 4)
    last = edited.at(N_FRAMES - 1)
    torch.testing.assert_close(late.means[late.node_mask(3)], last.means[last.node_mask(3)])
    _assert_unchanged(graph, before)
    # an ABSENT policy ends the inserted agent after its track
    gone = graph.with_node(_new_car(), track.with_policy(after=Extrapolation.ABSENT))
    assert 4 not in gone.at(11.0).included_nodes and 4 in gone.at(10.0).included_nodes


def test_time_before_after_and_between_frames_for_log_nodes() -> None:
    graph = make_graph()
    center, heading = rigid_track()
    objs, poses, alive = graph.object_poses_at(-3.0)  # before the axis: the first frame, held
    k = [n.node_id for n in objs].index(1)
    torch.testing.assert_close(poses[k, :3, 3], torch.tensor(center[0], dtype=torch.float32), atol=1e-5, rtol=0)
    objs, poses, alive = graph.object_poses_at(2.5)  # between frames: interpolated
    torch.testing.assert_close(poses[k, :3, 3], torch.tensor(0.5 * (center[2] + center[3]), dtype=torch.float32),
                               atol=1e-5, rtol=0)
    assert graph.resolve_time(-3.0).side == -1 and graph.resolve_time(9.0).side == 1
    assert graph.resolve_time(2.5).inside
    # a log node whose policy is ABSENT disappears outside the axis, HOLD nodes stay
    sign = graph.node(2)
    edited = graph.without([2]).with_node(dataclasses.replace(sign, extrapolation=Extrapolation.ABSENT))
    assert edited.present_nodes(9.0) == [0, 3] and edited.present_nodes(4.0) == [0, 2, 3]
    assert graph.present_nodes(9.0) == [0, 2, 3]


def test_with_poses_replaces_a_track_and_drops_the_refinement() -> None:
    graph = make_graph()
    refined = graph.node(1)
    refined.pose_deltas = torch.full((N_FRAMES, 6), 0.01)  # a trained refinement on this graph's node
    before = _snapshot(graph)
    edited = graph.with_poses(1, torch.as_tensor(_box(3.0, -1.0)))
    node = edited.node(1)
    assert node.pose_deltas is None and bool(node.present.all())
    composed = edited.at(4)  # the car was absent at frame 4 in the log; the new track has it
    assert 1 in composed.included_nodes
    torch.testing.assert_close(composed.means[composed.node_mask(1)][0], torch.tensor([3.0, -1.0, 0.8]),
                               atol=1e-5, rtol=0)
    assert graph.node(1) is refined and refined.pose_deltas is not None
    _assert_unchanged(graph, before)
    with pytest.raises(ValueError, match="background"):
        graph.with_poses(0, torch.as_tensor(_box(0, 0)))


def test_to_detached_and_metadata_return_new_graphs() -> None:
    graph = make_graph()
    for node in graph.nodes:
        node.gaussians.requires_grad_(True)
    before = _snapshot(graph)
    moved = graph.to("cpu")
    assert moved is not graph and all(a is not b for a, b in zip(moved.nodes, graph.nodes))
    frozen = graph.detached()
    assert not any(t.requires_grad for n in frozen.nodes for t in n.tensors().values())
    assert all(t.requires_grad for n in graph.nodes for _, t in n.gaussians.named_tensors())
    tagged = graph.with_metadata(note="edited")
    assert tagged.metadata["note"] == "edited" and "note" not in graph.metadata
    with pytest.raises(dataclasses.FrozenInstanceError):
        graph.eps2d = 0.1  # type: ignore[misc]
    _assert_unchanged(graph, before)


def test_nonrigid_is_not_rigid_and_offsets_loop_on_request() -> None:
    graph = make_graph()
    ped = graph.node(3)
    assert isinstance(ped, NonRigidNode) and isinstance(ped, ObjectNode) and not isinstance(ped, RigidNode)
    assert [n.node_id for n in graph.object_nodes] == [1, 2, 3]
    offsets = ped.offsets.detach()
    torch.testing.assert_close(ped.offsets_at(6.0), offsets[:, 2])  # HOLD: the last trained frame
    looped = dataclasses.replace(ped, offset_extrapolation=OffsetExtrapolation.LOOP)
    torch.testing.assert_close(looped.offsets_at(6.0), offsets[:, 1])  # period 4: 6 -> 2
    torch.testing.assert_close(looped.offsets_at(7.0), 0.5 * (offsets[:, 1] + offsets[:, 2]))
    torch.testing.assert_close(looped.offsets_at(3.0), ped.offsets_at(3.0))  # inside: unchanged


def test_records_round_trip_keeps_the_revision() -> None:
    edited = make_graph().without([2])
    back = SceneGraph.from_records(edited.to_records("rt"))
    assert back.revision == edited.revision and [n.node_id for n in back.nodes] == [0, 1, 3]
    assert "graph_revision" not in back.metadata


def test_pose_track_checks_its_shapes() -> None:
    with pytest.raises(ValueError, match="strictly increasing"):
        PoseTrack(np.array([0.0, 0.0]), torch.eye(4).repeat(2, 1, 1))
    with pytest.raises(ValueError, match=r"poses must be \[T=3, 4, 4\]"):
        PoseTrack(np.array([0.0, 1.0, 2.0]), torch.eye(4).repeat(2, 1, 1))
    track = PoseTrack(np.array([0.0, 1.0]), torch.eye(4).repeat(2, 1, 1), torch.tensor([True, False]))
    assert track.sample(0.0)[1] and not track.sample(0.5)[1] and not track.sample(3.0)[1]
