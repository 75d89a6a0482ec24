"""A tiny hand-made Argoverse 2 motion-forecasting scenario (Parquet + map archive) for loader tests.

The AV drives along city +x at 10 m/s from (100, 50) for 20 steps; track ``"7"`` (focal vehicle) drives 20 m
ahead of it, ``"8"`` (unscored pedestrian) stands at (110, 55), ``"9"`` (scored bus) appears at step 5. The map
is flat at z = 2: two vehicle lanes along y = 50 (``11`` -> ``12``), a bike lane, a crossing, a drivable area.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

SCENARIO_ID = "tiny-scenario"
STEPS = 20
START_NS = 1.6e17
GROUND_Z = 2.0


def scenario_columns() -> dict[str, list[Any]]:
    """The scenario table, column -> values (one row per track and step)."""
    rows: list[dict[str, Any]] = []

    def add(track_id: str, object_type: str, category: int, steps: range, x0: float, y: float, vx: float) -> None:
        for t in steps:
            rows.append({"observed": t < 10, "track_id": track_id, "object_type": object_type,
                         "object_category": category, "timestep": t, "position_x": x0 + vx * 0.1 * t,
                         "position_y": y, "heading": 0.0, "velocity_x": vx, "velocity_y": 0.0})

    add("AV", "vehicle", 1, range(STEPS), 100.0, 50.0, 10.0)
    add("7", "vehicle", 3, range(STEPS), 120.0, 50.0, 10.0)
    add("8", "pedestrian", 1, range(STEPS), 110.0, 55.0, 0.0)
    add("9", "bus", 2, range(5, STEPS), 150.0, 50.0, 5.0)
    columns = {name: [row[name] for row in rows] for name in rows[0]}
    n = len(rows)
    columns |= {"scenario_id": [SCENARIO_ID] * n, "start_timestamp": [START_NS] * n,
                "end_timestamp": [START_NS + (STEPS - 1) * 1e8] * n, "num_timestamps": [STEPS] * n,
                "focal_track_id": ["7"] * n, "city": ["pittsburgh"] * n, "map_id": [1] * n, "slice_id": ["s"] * n}
    return columns


def _segment(x0: float, y0: float, x1: float, y1: float) -> list[dict[str, float]]:
    return [{"x": x0, "y": y0, "z": GROUND_Z}, {"x": x1, "y": y1, "z": GROUND_Z}]


def map_archive() -> dict[str, Any]:
    """The map archive JSON object."""
    def lane(lane_id: int, lane_type: str, x0: float, x1: float, y: float, successors: list[int]) -> dict[str, Any]:
        return {"id": lane_id, "lane_type": lane_type, "is_intersection": False,
                "left_lane_boundary": _segment(x0, y + 1.75, x1, y + 1.75),
                "right_lane_boundary": _segment(x0, y - 1.75, x1, y - 1.75),
                "successors": successors, "predecessors": [],
                "centerline": [{"x": x0, "y": y, "z": 0.0}, {"x": x1, "y": y, "z": 0.0}]}

    return {
        "lane_segments": {"11": lane(11, "VEHICLE", 90.0, 140.0, 50.0, [12, 13]),
                          "12": lane(12, "VEHICLE", 140.0, 190.0, 50.0, []),
                          "13": lane(13, "BIKE", 140.0, 190.0, 53.0, [])},
        "pedestrian_crossings": {"21": {"id": 21, "edge1": _segment(130.0, 46.0, 130.0, 54.0),
                                        "edge2": _segment(133.0, 46.0, 133.0, 54.0)}},
        "drivable_areas": {"31": {"id": 31, "area_boundary": [
            {"x": 90.0, "y": 46.0, "z": GROUND_Z}, {"x": 190.0, "y": 46.0, "z": GROUND_Z},
            {"x": 190.0, "y": 54.0, "z": GROUND_Z}, {"x": 90.0, "y": 54.0, "z": GROUND_Z}]}},
    }


def write_scenario(folder: Path, columns: dict[str, list[Any]] | None = None,
                   archive: dict[str, Any] | None = None, scenario_id: str = SCENARIO_ID) -> Path:
    """Write ``scenario_<id>.parquet`` and ``log_map_archive_<id>.json`` into ``folder`` (created); returns it.

    ``columns`` / ``archive`` default to ``scenario_columns()`` / ``map_archive()``; ``archive=None`` with a map
    is the default, pass ``{}`` for no map file at all.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    folder.mkdir(parents=True, exist_ok=True)
    columns = scenario_columns() if columns is None else columns
    pq.write_table(pa.table(columns), folder / f"scenario_{scenario_id}.parquet")
    archive = map_archive() if archive is None else archive
    if archive:
        (folder / f"log_map_archive_{scenario_id}.json").write_text(json.dumps(archive))
    return folder


def changed(columns: dict[str, list[Any]], name: str, row: int, value: Any) -> dict[str, list[Any]]:
    """A copy of ``columns`` with ``columns[name][row] = value``."""
    out = copy.deepcopy(columns)
    out[name][row] = value
    return out
