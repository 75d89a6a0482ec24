"""``Scenario`` decoding and loader errors on small hand-encoded scenarios (no sample data needed)."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError, load_waymo_scenario
from simsplat_core.data.protowire import ProtoDecodeError
from simsplat_core.data.tfrecord import encode_tfrecord
from simsplat_core.data.waymo_scenario_proto import parse_scenario
from tests.simsplat_core.data.test_protowire import ld, tag, varint

STEP_S = 0.1


def _double(number: int, value: float) -> bytes:
    return tag(number, 1) + struct.pack("<d", value)


def _float(number: int, value: float) -> bytes:
    return tag(number, 5) + struct.pack("<f", value)


def _int(number: int, value: int) -> bytes:
    return tag(number, 0) + varint(value)


def _state(x: float, y: float, heading: float, valid: bool = True) -> bytes:
    return (
        _double(2, x) + _double(3, y) + _double(4, 1.0)
        + _float(5, 4.5) + _float(6, 2.0) + _float(7, 1.6) + _float(8, heading)
        + _float(9, 10.0) + _float(10, 0.0) + _int(11, int(valid))
    )  # fmt: skip


def _track(track_id: int, object_type: int, states: list[bytes]) -> bytes:
    return _int(1, track_id) + _int(2, object_type) + b"".join(ld(3, s) for s in states)


def _scenario(sdc_valid: tuple[bool, ...] = (True, True, True), sdc_index: int = 0) -> bytes:
    steps = len(sdc_valid)
    timestamps = ld(1, struct.pack(f"<{steps}d", *(i * STEP_S for i in range(steps))))
    sdc = _track(7, 1, [_state(100.0 + i, 50.0, np.pi / 2, v) for i, v in enumerate(sdc_valid)])
    other = _track(8, 2, [_state(100.0, 60.0 + i, 0.0, i > 0) for i in range(steps)])
    lane = ld(3, ld(8, _double(1, 100.0) + _double(2, 40.0)) + ld(8, _double(1, 100.0) + _double(2, 80.0)))
    return (
        timestamps + ld(2, sdc) + ld(2, other) + ld(5, b"abc") + _int(6, sdc_index)
        + ld(8, _int(1, 11) + lane) + _int(10, 1)
    )  # fmt: skip


def test_parse_minimal_scenario() -> None:
    scenario = parse_scenario(_scenario())
    assert scenario.scenario_id == "abc" and scenario.current_time_index == 1
    assert [t.track_id for t in scenario.tracks] == [7, 8]
    np.testing.assert_array_equal(scenario.tracks[1].valid, [False, True, True])
    (lane,) = scenario.map_features
    assert lane.kind == "lane" and lane.feature_id == 11 and lane.points.shape == (2, 3)


def test_load_moves_everything_to_the_first_sdc_pose(tmp_path: Path) -> None:
    path = tmp_path / "mini.tfrecord"
    path.write_bytes(encode_tfrecord(_scenario()))
    log = load_waymo_scenario(path)
    np.testing.assert_array_equal(log.ego_poses[0], np.eye(4))
    # The SDC heads along global +y, so global +x is world -y; it moves 1 m per step along global +x.
    np.testing.assert_allclose(log.ego_poses[2][:3, 3], [0.0, -2.0, 0.0], atol=1e-6)  # float32 heading
    (track,) = log.tracks
    np.testing.assert_array_equal(track.frame_idx, [1, 2])  # invalid step 0 is an absent frame
    np.testing.assert_allclose(track.center[0], [11.0, 0.0, 0.8], atol=1e-6)  # 11 m ahead; ego origin on the ground
    np.testing.assert_allclose(track.heading, -np.pi / 2, atol=1e-6)
    np.testing.assert_allclose(track.speed, 10.0)
    assert log.object("8").category == "pedestrian"
    (lane,) = log.map_features
    np.testing.assert_allclose(lane.points[:, :2], [[-10.0, 0.0], [30.0, 0.0]], atol=1e-5)


def test_sdc_invalid_at_a_step_names_the_state(tmp_path: Path) -> None:
    path = tmp_path / "sdc_gap.tfrecord"
    path.write_bytes(encode_tfrecord(_scenario(sdc_valid=(True, False, True))))
    with pytest.raises(CorruptLogError, match=r"field 'Scenario\.tracks\[0\]\.states\[1\]\.valid'"):
        load_waymo_scenario(path)


def test_out_of_range_sdc_index() -> None:
    with pytest.raises(ProtoDecodeError, match="sdc_track_index"):
        parse_scenario(_scenario(sdc_index=5))
