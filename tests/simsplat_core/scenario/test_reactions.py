"""What an edit changed, agent by agent: a refined car that stops, slows or swerves is a reaction to the nearest
edited, inserted or removed agent; unchanged agents are not listed; deviations and speeds are measured."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.reactions import REMOVED, agent_changes

T = 20
DT = 0.1


def _states(agents: dict[str, tuple[str, np.ndarray]], speeds: dict[str, np.ndarray]) -> AgentStates:
    """Agents ``id -> (source, [T, 2] xy)`` moving along +x, with ``[T]`` speeds."""
    ids = tuple(agents)
    return AgentStates(object_ids=ids, categories=("vehicle",) * len(ids),
                       sources=tuple(agents[o][0] for o in ids), node_ids=np.full(len(ids), -1),
                       frame_idx=np.arange(T), times=np.arange(T) * DT,
                       xy=np.stack([agents[o][1] for o in ids]), z=np.zeros((len(ids), T)),
                       heading=np.zeros((len(ids), T)), speed=np.stack([speeds[o] for o in ids]),
                       size=np.tile([4.5, 2.0, 1.5], (len(ids), 1)), valid=np.ones((len(ids), T), bool))


def _drive(x0: float, speed: float, y: float = 0.0) -> np.ndarray:
    return np.stack([x0 + speed * DT * np.arange(T), np.full(T, y)], axis=-1)


LOG = _states({"car": ("log", _drive(0.0, 10.0)), "parked": ("log", _drive(60.0, 0.0, y=5.0)),
               "other": ("log", _drive(-50.0, 5.0, y=-20.0))},
              {"car": np.full(T, 10.0), "parked": np.zeros(T), "other": np.full(T, 5.0)})


def _stopping() -> tuple[np.ndarray, np.ndarray]:
    speed = np.concatenate([np.full(5, 10.0), np.linspace(10.0, 0.0, 10), np.zeros(5)])
    x = np.concatenate([[0.0], np.cumsum(speed[:-1] * DT)])
    return np.stack([x, np.zeros(T)], axis=-1), speed


def test_a_car_stopping_for_an_inserted_cone_reacts_to_it() -> None:
    xy, speed = _stopping()
    cone = np.tile([12.0, 0.0], (T, 1))
    edited = _states({"car": ("refined", xy), "parked": ("log", LOG.xy[1]), "other": ("log", LOG.xy[2]),
                      "cone": ("inserted", cone)},
                     {"car": speed, "parked": np.zeros(T), "other": np.full(T, 5.0), "cone": np.zeros(T)})
    changes = {c.object_id: c for c in agent_changes(edited, LOG)}
    assert set(changes) == {"car", "cone"}  # unchanged agents are not listed
    car = changes["car"]
    assert car.reaction == "stopped" and car.reacts_to == "cone"
    assert car.min_speed == 0.0 and car.log_min_speed == pytest.approx(10.0)
    assert car.max_deviation_m == pytest.approx(np.linalg.norm(LOG.xy[0, -1] - xy[-1]))
    assert car.path_offset_m < 0.5  # it stayed on its log path: not a detour
    assert car.reaction_frame is not None and 5 <= car.reaction_frame < T
    assert changes["cone"].source == "inserted" and np.isnan(changes["cone"].max_deviation_m)


def test_a_swerve_is_a_detour_and_a_removed_agent_can_be_the_cause() -> None:
    swerve = LOG.xy[0].copy()
    swerve[8:, 1] = 2.5
    edited = _states({"car": ("refined", swerve), "other": ("log", LOG.xy[2])},
                     {"car": np.full(T, 10.0), "other": np.full(T, 5.0)})
    changes = agent_changes(edited, LOG)
    assert [(c.object_id, c.source) for c in changes] == [("parked", REMOVED), ("car", "refined")]
    car = changes[1]
    assert car.reaction == "detoured" and car.reacts_to == "parked" and car.reaction_frame == 8
    assert car.path_offset_m == pytest.approx(2.5)


def test_a_slower_car_on_its_own_path_slowed() -> None:
    edited = _states({"car": ("refined", _drive(0.0, 7.0)), "parked": ("edited", LOG.xy[1] + [0.0, -2.0]),
                      "other": ("log", LOG.xy[2])},
                     {"car": np.full(T, 7.0), "parked": np.zeros(T), "other": np.full(T, 5.0)})
    car = next(c for c in agent_changes(edited, LOG) if c.object_id == "car")
    assert car.reaction == "slowed" and car.reacts_to == "parked"


def test_states_on_other_steps_are_refused() -> None:
    with pytest.raises(ValueError, match="steps"):
        agent_changes(_states({"car": ("log", LOG.xy[0][:T])}, {"car": np.zeros(T)}),
                      dataclasses.replace(LOG, times=LOG.times[:5], frame_idx=LOG.frame_idx[:5], xy=LOG.xy[:, :5],
                                          z=LOG.z[:, :5], heading=LOG.heading[:, :5], speed=LOG.speed[:, :5],
                                          valid=LOG.valid[:, :5]))
