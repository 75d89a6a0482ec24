"""Grounding metrics on hand-made masks: accuracy sets, 4D LangSplat's vIoU, the overlap fast path, the runner."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.eval.grounding.benchmark import GroundingBenchmark, GroundingQuery, SceneGroundTruth
from simsplat_core.eval.grounding.metrics import (
    OverlapCounts,
    QueryOutcome,
    evaluate_grounding,
    frame_ious,
    query_correct,
    summarise,
    viou,
)
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage


def _masks(frames: int = 3, cameras: int = 2, h: int = 4, w: int = 5) -> np.ndarray:
    return np.zeros((frames, cameras, h, w), dtype=bool)


def test_accuracy_compares_object_sets() -> None:
    assert query_correct(["a"], ["a"])
    assert not query_correct(["a", "b"], ["a"])  # a look-alike returned as well
    assert not query_correct(["b"], ["a"])
    assert query_correct(["b", "a"], ("a", "b"))  # group, any order
    assert not query_correct(["a"], ["a", "b"])  # group, one member missing
    assert query_correct([], [])  # no-match query answered with nothing
    assert not query_correct(["a"], [])


def test_viou_counts_frames_where_only_one_side_is_non_empty() -> None:
    pred, gt = _masks(), _masks()
    # frame 0: both non-empty, IoU = 2 / 4
    pred[0, 0, 0, 0:3] = True
    gt[0, 0, 0, 1:4] = True
    # frame 1: ground truth only -> in S_U, not in S_I
    gt[1, 1, 2, 2] = True
    # frame 2: both empty -> in neither
    assert viou(pred, gt) == pytest.approx(0.5 / 2)
    inter, union, iou = frame_ious(pred, gt)
    assert inter.tolist() == [2, 0, 0]
    assert union.tolist() == [4, 1, 0]
    assert iou.tolist() == pytest.approx([0.5, 0.0, 0.0])


def test_viou_pools_all_cameras_of_a_frame() -> None:
    pred, gt = _masks(frames=1), _masks(frames=1)
    pred[0, 0, :2] = True  # 10 pixels in camera 0
    gt[0, 1, :2] = True  # 10 pixels in camera 1
    assert viou(pred, gt) == 0.0
    gt[0, 0, :2] = True  # now camera 0 matches too: IoU = 10 / 20
    assert viou(pred, gt) == pytest.approx(0.5)


def test_viou_of_empty_and_spurious_predictions() -> None:
    empty = _masks()
    assert viou(empty, empty) == 1.0  # a no-match query answered with nothing
    spurious = _masks()
    spurious[2, 0, 1, 1] = True
    assert viou(spurious, empty) == 0.0
    assert viou(empty, spurious) == 0.0
    assert viou(spurious, spurious) == 1.0


def test_viou_rejects_mismatched_shapes() -> None:
    with pytest.raises(ValueError, match="differ in shape"):
        viou(_masks(frames=2), _masks(frames=3))


def _truth(maps: np.ndarray) -> SceneGroundTruth:
    return SceneGroundTruth(
        "seq", np.arange(maps.shape[0], dtype=np.int64), tuple(f"cam{i}" for i in range(maps.shape[1])), maps,
        {"car": 1, "ped": 2, "far": 5},
    )


def test_overlap_counts_agree_with_explicit_masks() -> None:
    rng = np.random.default_rng(0)
    node_maps = rng.choice(np.array([-1, 0, 3, 4, 7], dtype=np.int32), size=(4, 2, 6, 7))
    inst_maps = rng.choice(np.array([0, 1, 2, 5], dtype=np.int32), size=(4, 2, 6, 7))
    inst_maps[1] = 0  # a frame without any object
    node_maps[3] = -1  # a frame where nothing was rendered
    truth = _truth(inst_maps)
    overlap = OverlapCounts.build(node_maps, truth)
    for nodes in [(3,), (4, 7), (), (0,), (3, 99)]:
        for targets in [("car",), ("car", "ped"), (), ("far",)]:
            explicit = viou(np.isin(node_maps, np.asarray(nodes, dtype=np.int32)), truth.masks(targets))
            assert overlap.viou(nodes, targets) == pytest.approx(explicit), (nodes, targets)


def _query(text: str, targets: tuple[str, ...], category: str, kind: str) -> GroundingQuery:
    return GroundingQuery("seq", text, "definite", targets, kind, category, (), "app", f"seq/{text}")


def test_summarise_per_category_and_total() -> None:
    car = _query("car", ("car",), "vehicle", "single")
    ped = _query("ped", ("ped",), "pedestrian", "single")
    none = _query("nothing", (), "vehicle", "none")
    outcomes = [
        QueryOutcome("m", car, ("car",), True, 0.8, 0.0),
        QueryOutcome("m", none, ("car",), False, 0.0, 0.0),
        QueryOutcome("m", ped, ("ped",), True, 0.6, 0.0),
    ]
    s = summarise(outcomes)["m"]
    assert s["vehicle"].queries == 2 and s["vehicle"].accuracy == pytest.approx(0.5)
    assert s["vehicle"].viou == pytest.approx(0.4)
    assert s["pedestrian"].accuracy == 1.0 and s["pedestrian"].viou == pytest.approx(0.6)
    assert s["total"].queries == 3 and s["total"].accuracy == pytest.approx(2 / 3)


class _Fixed:
    """Answers every query with a fixed node set (by query text)."""

    def __init__(self, answers: dict[str, tuple[int, ...]]) -> None:
        self.answers = answers

    def ground(self, scene: LanguageScene, text: str) -> tuple[int, ...]:
        return self.answers[text]


def test_evaluate_grounding_maps_nodes_to_objects_and_scores_masks() -> None:
    inst = np.zeros((2, 1, 4, 4), dtype=np.int32)
    inst[:, 0, 0, :2] = 1  # car: 2 px per frame
    inst[0, 0, 3, :] = 2  # ped: 4 px in frame 0
    nodes_map = np.zeros_like(inst)
    nodes_map[:, 0, 0, :2] = 11  # node 11 renders the car exactly
    nodes_map[0, 0, 3, :3] = 12  # node 12 renders 3 of the pedestrian's 4 pixels
    truth = _truth(inst)

    def node(nid: int, oid: str, cat: str) -> NodeLanguage:
        return NodeLanguage(nid, oid, cat, cat, None, None, None)

    scene = LanguageScene("seq", "", (node(11, "car", "vehicle"), node(12, "ped", "pedestrian")),
                          np.arange(2), ("cam0",), nodes_map, "enc")
    queries = (
        _query("the car", ("car",), "vehicle", "single"),
        _query("the walker", ("ped",), "pedestrian", "single"),
        _query("everyone", ("car", "ped"), "vehicle", "group"),
        _query("a bus", (), "vehicle", "none"),
    )
    bench = GroundingBenchmark(queries, {"seq": truth})
    answers = {"the car": (11,), "the walker": (12,), "everyone": (11,), "a bus": ()}
    results = evaluate_grounding([scene], bench, {"fixed": _Fixed(answers)})
    by_text = {o.query.text: o for o in results.outcomes}
    assert by_text["the car"].correct and by_text["the car"].viou == pytest.approx(1.0)
    assert by_text["the walker"].correct and by_text["the walker"].viou == pytest.approx(0.75)
    assert not by_text["everyone"].correct and by_text["everyone"].predicted == ("car",)
    # frame 0: IoU 2/6, frame 1: 2/2 -> (1/3 + 1) / 2
    assert by_text["everyone"].viou == pytest.approx((2 / 6 + 1.0) / 2)
    assert by_text["a bus"].correct and by_text["a bus"].viou == 1.0
    with pytest.raises(KeyError, match="no object nodes"):
        evaluate_grounding([scene], bench, {"bad": _Fixed({**answers, "a bus": (99,)})})


def test_ground_truth_alignment_to_scene_frames_and_cameras() -> None:
    inst = np.arange(2 * 3 * 2 * 2, dtype=np.int32).reshape(3, 2, 2, 2)
    truth = _truth(inst)
    sub = truth.aligned_to(np.array([2, 0]), ("cam1",))
    assert sub.instance_maps.shape == (2, 1, 2, 2)
    assert np.array_equal(sub.instance_maps[0, 0], inst[2, 1])
    with pytest.raises(ValueError, match="frames"):
        truth.aligned_to(np.array([7]), ("cam0",))
    with pytest.raises(ValueError, match="cameras"):
        truth.aligned_to(np.array([0]), ("rear",))
