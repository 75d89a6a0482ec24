"""Agent geometry: oriented-box overlap and signed distances to the drivable area."""

from __future__ import annotations

import numpy as np

from simsplat_core.scenario.geometry import box_footprints, corner_road_distances, footprints_overlap, offroad


def test_oriented_boxes_overlap_by_separating_axes() -> None:
    a = np.zeros((3, 2))
    b = np.array([[4.0, 0.0], [4.0, 0.0], [3.0, 3.0]])
    heading_b = np.array([0.0, np.pi / 2, np.pi / 4])
    hit = footprints_overlap(a, np.zeros(3), (4.0, 2.0), b, heading_b, (4.0, 2.0))
    # end to end: touching at x = 2 overlaps; b turned 90 degrees spans x 3..5 (1 m gap); b at (3, 3) is clear
    assert hit.tolist() == [True, False, False]
    assert footprints_overlap(
        a[:1], np.zeros(1), (4.0, 2.0), b[1:2], heading_b[1:2], (4.0, 2.0), margin=1.1
    ).tolist() == [True]


def test_corner_distances_and_offroad() -> None:
    road = [np.array([[-50.0, -5.0], [50.0, -5.0], [50.0, 5.0], [-50.0, 5.0]])]
    centers = np.array([[0.0, 0.0], [0.0, 4.5]])
    d = corner_road_distances(centers, np.zeros(2), (4.0, 2.0), road)  # [2, 4]
    np.testing.assert_allclose(d[0], 4.0)  # every corner 4 m inside the kerb
    np.testing.assert_allclose(np.sort(d[1]), [-0.5, -0.5, 1.5, 1.5])
    assert offroad(centers, np.zeros(2), (4.0, 2.0), road).tolist() == [False, True]
    assert offroad(centers, np.zeros(2), (4.0, 2.0), road, tolerance_m=0.6).tolist() == [False, False]
    corners = box_footprints(np.zeros(2), 0.0, (4.0, 2.0))
    assert corners.shape == (4, 2) and np.allclose(np.abs(corners), [2.0, 1.0])

