"""The reactive model's named parameters: the published defaults the docstrings cite, and the orderings the
algorithm relies on (floors below the values they bound, pedestrians gentler than cars)."""

from __future__ import annotations

import dataclasses

import pytest

from simsplat_core.motion.traffic_params import (
    GapAcceptanceParams,
    IDMParams,
    LaneChangeParams,
    PedestrianParams,
    ReactiveParams,
)


def test_idm_defaults_are_treibers_published_values() -> None:
    p = IDMParams()
    assert (p.desired_time_headway_s, p.min_gap_m, p.max_accel_mps2, p.comfortable_decel_mps2,
            p.accel_exponent) == (1.5, 2.0, 1.5, 2.0, 4.0)


def test_mobil_and_gap_acceptance_defaults_are_the_cited_ones() -> None:
    lc = LaneChangeParams()
    assert (lc.politeness, lc.threshold_mps2, lc.safe_decel_mps2, lc.duration_s) == (0.3, 0.2, 4.0, 3.0)
    assert GapAcceptanceParams().critical_gap_s == 4.0


@pytest.mark.parametrize("p", [IDMParams(), PedestrianParams().following], ids=["vehicle", "pedestrian"])
def test_floors_lie_below_the_values_they_bound(p: IDMParams) -> None:
    """``IDMArrays.calibrated`` clips the headway and gap between these; the positional bound lies inside the gap."""
    assert 0 < p.min_time_headway_s <= p.desired_time_headway_s
    assert 0 < p.standstill_clearance_m <= p.min_standstill_gap_m <= p.min_gap_m
    assert 0 < p.comfortable_decel_mps2 <= p.max_decel_mps2


def test_pedestrians_follow_more_gently_and_closer_than_cars() -> None:
    car, walker = IDMParams(), PedestrianParams().following
    assert walker.max_accel_mps2 < car.max_accel_mps2 and walker.max_decel_mps2 < car.max_decel_mps2
    assert walker.min_gap_m < car.min_gap_m and walker.desired_time_headway_s < car.desired_time_headway_s


def test_parameters_are_frozen_and_not_shared_between_instances() -> None:
    a, b = ReactiveParams(), ReactiveParams()
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.idm.min_gap_m = 1.0  # type: ignore[misc]
    custom = dataclasses.replace(a, idm=IDMParams(min_gap_m=3.0))
    assert custom.idm.min_gap_m == 3.0 and b.idm.min_gap_m == 2.0 and a.idm.min_gap_m == 2.0
