"""RefAV's balanced accuracies on hand-made predictions whose answers are counted by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simsplat_core.eval.search.metrics import balanced_accuracy, log_ba, timestamp_ba


def _b(*values: int) -> np.ndarray:
    return np.array(values, dtype=bool)


def test_perfect_and_inverted_predictions() -> None:
    truth = _b(1, 0, 1, 0, 0)
    assert balanced_accuracy(truth, truth) == 1.0
    assert balanced_accuracy(truth, ~truth) == 0.0


def test_predicting_one_class_everywhere_scores_one_half() -> None:
    truth = _b(1, 0, 0, 0, 0, 0, 0, 0, 0, 0)  # 1 positive, 9 negatives: plain accuracy would reward "never"
    assert balanced_accuracy(truth, np.zeros(10, bool)) == pytest.approx(0.5)  # TPR 0, TNR 1
    assert balanced_accuracy(truth, np.ones(10, bool)) == pytest.approx(0.5)  # TPR 1, TNR 0


def test_rates_are_averaged_not_the_frames() -> None:
    # 4 positives, 2 found (TPR 2/4); 2 negatives, 1 kept negative (TNR 1/2)
    truth = _b(1, 1, 1, 1, 0, 0)
    pred = _b(1, 1, 0, 0, 1, 0)
    assert balanced_accuracy(truth, pred) == pytest.approx((2 / 4 + 1 / 2) / 2)


def test_a_class_that_is_absent_is_left_out() -> None:
    # a negative query: only the true-negative rate counts (3 of 4 frames correctly empty)
    assert balanced_accuracy(_b(0, 0, 0, 0), _b(0, 1, 0, 0)) == pytest.approx(3 / 4)
    # every frame positive: only the true-positive rate counts (1 of 2)
    assert balanced_accuracy(_b(1, 1), _b(1, 0)) == pytest.approx(1 / 2)
    assert math.isnan(balanced_accuracy(_b(), _b()))


def test_shapes_are_flattened_but_sizes_must_match() -> None:
    truth = np.array([[True, False], [False, False]])
    assert balanced_accuracy(truth, truth.ravel()) == 1.0
    with pytest.raises(ValueError, match="truth has 3 entries, predicted 2"):
        balanced_accuracy(_b(1, 0, 1), _b(1, 0))


def test_timestamp_ba_pools_every_frame_of_every_log() -> None:
    truth = [_b(1, 1, 0), _b(0, 0, 0, 0)]  # 2 positive frames, 5 negative frames over both logs
    pred = [_b(1, 0, 0), _b(1, 1, 0, 0)]  # 1 of 2 positives found; 3 of 5 negatives kept
    assert timestamp_ba(truth, pred) == pytest.approx((1 / 2 + 3 / 5) / 2)


def test_log_ba_asks_only_whether_a_log_holds_the_scenario() -> None:
    truth = [_b(0, 1, 0), _b(0, 0, 0), _b(0, 0, 0), _b(1, 0, 0)]  # logs 0 and 3 hold it
    pred = [_b(1, 0, 0), _b(0, 0, 0), _b(0, 0, 1), _b(0, 0, 0)]  # a hit at the wrong frame still finds log 0
    # positives: log 0 found, log 3 missed -> 1/2; negatives: log 1 empty, log 2 hit -> 1/2
    assert log_ba(truth, pred) == pytest.approx(0.5)
    # per frame: neither positive frame hit (0/2), 8 of the 10 negative frames kept
    assert timestamp_ba(truth, pred) == pytest.approx((0 / 2 + 8 / 10) / 2)
