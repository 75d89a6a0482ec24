"""A landing folder for tests: the real Waymo motion scenario and AV2 forecasting samples and one bad log."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

WAYMO_SCENARIO = "waymo/motion_data_one_scenario.tfrecord"
AV2_FORECASTING = "av2/forecasting-0a1e6f0a"


def bad_scenario(folder: Path) -> Path:
    """A folder that looks like an AV2 forecasting scenario (the columns detection checks) but lacks positions."""
    folder.mkdir(parents=True)
    pq.write_table(pa.table({"track_id": ["a"], "timestep": [0], "focal_track_id": ["a"]}),
                   folder / "scenario_bad.parquet")
    return folder


def make_landing(shared_data: Path, folder: Path) -> Path:
    """``folder`` holding ``motion.tfrecord`` and ``forecasting/`` (symlinks to the samples) and ``broken/``."""
    folder.mkdir(parents=True)
    (folder / "motion.tfrecord").symlink_to(shared_data / WAYMO_SCENARIO)
    (folder / "forecasting").symlink_to(shared_data / AV2_FORECASTING, target_is_directory=True)
    bad_scenario(folder / "broken")
    return folder
