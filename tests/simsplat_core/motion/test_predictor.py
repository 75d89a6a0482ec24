"""The predictor protocol's request and answer types."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.motion.predictor import MotionMap, MotionPredictor, Rollout, RolloutRequest
from tests.simsplat_core.motion.scenes import CAR, TIMES, T, road, states, track


def _states():
    return states([("ego", "vehicle", track(10.0 * TIMES, 0.0), CAR), ("a", "vehicle", track(8.0 * TIMES, 3.5), CAR),
                   ("b", "vehicle", track(5.0 * TIMES, 3.5), CAR)])


@pytest.mark.parametrize("start", [0, T])
def test_start_step_must_leave_history_and_a_future(start: int) -> None:
    with pytest.raises(ValueError, match=rf"start_step must be in \[1, {T - 1}\], got {start}"):
        RolloutRequest(_states(), start, np.array([0]), road())


@pytest.mark.parametrize("rows", [[3], [-1]])
def test_fixed_rows_must_index_the_agents(rows: list[int]) -> None:
    with pytest.raises(ValueError, match="fixed_rows must index the 3 agents"):
        RolloutRequest(_states(), 5, np.array(rows), road())


def test_free_rows_are_the_other_rows_in_order() -> None:
    assert RolloutRequest(_states(), 5, np.array([1]), road()).free_rows.tolist() == [0, 2]
    assert RolloutRequest(_states(), 5, np.array([], dtype=np.int64), road()).free_rows.tolist() == [0, 1, 2]
    assert RolloutRequest(_states(), T - 1, np.array([0, 1, 2]), road()).free_rows.size == 0


def test_a_map_without_road_edges_has_an_empty_edge_array() -> None:
    mp = road()
    assert isinstance(mp, MotionMap) and mp.road_edges.shape == (0, 2, 2)


def test_the_protocol_is_structural() -> None:
    class Replay:
        name = "replay"

        def rollout(self, request: RolloutRequest) -> Rollout:
            return Rollout(request.states, {}, self.name)

    class Nameless:
        def rollout(self, request: RolloutRequest) -> Rollout:
            return Rollout(request.states, {}, "")

    assert isinstance(Replay(), MotionPredictor)
    assert not isinstance(Nameless(), MotionPredictor)
