"""Small ``ExportScenario`` fixtures for the export format tests."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.export.record import ExportMapFeature, ExportScenario, SignalState


def make_scenario(num_agents: int = 3, num_steps: int = 91, *, seed: int = 0,
                  scenario_id: str = "seq-a/edit-1/1/w0") -> ExportScenario:
    """A scenario of ``num_agents`` cars driving along +x (row 0 the SDC), one pedestrian when ``num_agents``
    > 2, two lanes, a road edge, a road line, a crosswalk, a stop sign, a speed bump and one signal."""
    rng = np.random.default_rng(seed)
    t = np.arange(num_steps) * 0.1
    states = np.zeros((num_agents, num_steps, 9))
    valid = np.ones((num_agents, num_steps), bool)
    types = []
    for a in range(num_agents):
        pedestrian = a == 2
        speed = 1.4 if pedestrian else 5.0 + rng.uniform(0, 5)
        heading = np.pi / 2 if pedestrian else 0.0
        x0, y0 = (20.0, -6.0) if pedestrian else (10.0 * a, 0.0 if a % 2 == 0 else 3.5)
        states[a, :, 0] = x0 + speed * t * np.cos(heading)
        states[a, :, 1] = y0 + speed * t * np.sin(heading)
        states[a, :, 2] = 0.8
        states[a, :, 3:6] = (0.6, 0.6, 1.7) if pedestrian else (4.5, 1.9, 1.6)
        states[a, :, 6] = heading
        states[a, :, 7] = speed * np.cos(heading)
        states[a, :, 8] = speed * np.sin(heading)
        types.append("pedestrian" if pedestrian else "vehicle")
    if num_agents > 1:
        valid[-1, :5] = False
        states[-1, :5] = 0.0
    xs = np.linspace(-20, 200, 12)
    lane0 = np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)], 1)
    lane1 = lane0 + [0, 3.5, 0]
    features = (
        ExportMapFeature(100, "lane", lane0, type="TYPE_SURFACE_STREET", left_neighbors=(101,), exit_lanes=(),
                         speed_limit_mph=25.0, source_id="lane_100"),
        ExportMapFeature(101, "lane", lane1, type="TYPE_SURFACE_STREET", right_neighbors=(100,),
                         source_id="lane_101"),
        ExportMapFeature(200, "road_edge", lane0 - [0, 1.8, 0], type="TYPE_ROAD_EDGE_BOUNDARY"),
        ExportMapFeature(300, "road_line", lane0 + [0, 1.75, 0], type="TYPE_BROKEN_SINGLE_WHITE"),
        ExportMapFeature(400, "crosswalk", np.array([[18, -4, 0], [22, -4, 0], [22, 6, 0], [18, 6, 0.0]])),
        ExportMapFeature(500, "stop_sign", np.array([[60.0, -2.5, 0.0]]), controlled_lanes=(100,)),
        ExportMapFeature(600, "speed_bump", np.array([[80, -2, 0], [81, -2, 0], [81, 5, 0], [80, 5, 0.0]])),
    )
    signal = SignalState(101, "LANE_STATE_GO", np.array([100.0, 3.5, 0.0]))
    return ExportScenario(
        scenario_id=scenario_id,
        timestamps_s=t,
        current_time_index=min(10, num_steps - 1),
        track_ids=np.arange(num_agents, dtype=np.int64) + 7,
        agent_types=tuple(types),
        states=states,
        valid=valid,
        sdc_index=0,
        objects_of_interest=(8,) if num_agents > 1 else (),
        tracks_to_predict=(1,) if num_agents > 1 else (),
        track_sources=("log",) + ("edited",) + ("log",) * (num_agents - 2) if num_agents > 1 else ("log",),
        source_object_ids=("ego",) + tuple(f"obj{a}" for a in range(1, num_agents)),
        map_features=features,
        signals=tuple((signal,) for _ in range(num_steps)),
        metadata={"seq_id": "seq-a", "source": "synthetic"},
    )


@pytest.fixture
def scenario() -> ExportScenario:
    return make_scenario()
