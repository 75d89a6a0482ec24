"""Real driving-log loaders: Waymo ``Frame`` and Open Motion ``Scenario`` TFRecords, Argoverse 2 sensor logs and
motion-forecasting scenarios, and the registry that names them (``registry.LOG_SOURCES``).

Every loader returns a validated ``simsplat_core.types.SceneLog`` in the shared conventions (world =
first ego pose, OpenCV cameras) and raises ``CorruptLogError`` for a damaged or malformed file.
"""

from simsplat_core.data.av2 import load_av2_log
from simsplat_core.data.av2_forecasting import load_av2_forecasting
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.data.waymo import load_waymo_frames
from simsplat_core.data.waymo_scenario import load_waymo_scenario

__all__ = ["CorruptLogError", "load_av2_forecasting", "load_av2_log", "load_waymo_frames", "load_waymo_scenario"]
