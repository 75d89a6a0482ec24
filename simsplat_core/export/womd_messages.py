"""Waymo Open Motion's ``Scenario`` messages as protobuf runtime classes, for writing WOMD shards.

Defined from the decoder's schemas (``simsplat_core.data.waymo_scenario_proto``, the project's one definition of
the format) through ``schema_messages``; the classes live in a private descriptor pool under the public package
name ``waymo.open_dataset``, so the bytes they serialize are read by any WOMD reader (Waymo's own ``scenario_pb2``,
SMART, MTR, GPUDrive, ScenarioNet) and by ``parse_scenario``. Enum fields take the value numbers of the schemas'
``EnumSchema`` s.
"""

from __future__ import annotations

from typing import Any

from simsplat_core.data.waymo_scenario_proto import SCENARIO
from simsplat_core.export.schema_messages import message_classes

#: The protobuf package of the public protos.
WOMD_PACKAGE = "waymo.open_dataset"
#: The name of the file descriptor holding the classes (in a private pool).
WOMD_FILE_NAME = "simsplat/womd_scenario.proto"

_CLASSES: dict[str, Any] = message_classes(WOMD_FILE_NAME, WOMD_PACKAGE, (SCENARIO,))

Scenario = _CLASSES["Scenario"]
Track = _CLASSES["Track"]
ObjectState = _CLASSES["ObjectState"]
RequiredPrediction = _CLASSES["RequiredPrediction"]
DynamicMapState = _CLASSES["DynamicMapState"]
TrafficSignalLaneState = _CLASSES["TrafficSignalLaneState"]
MapFeature = _CLASSES["MapFeature"]
MapPoint = _CLASSES["MapPoint"]
LaneCenter = _CLASSES["LaneCenter"]
LaneNeighbor = _CLASSES["LaneNeighbor"]
BoundarySegment = _CLASSES["BoundarySegment"]
RoadLine = _CLASSES["RoadLine"]
RoadEdge = _CLASSES["RoadEdge"]
StopSign = _CLASSES["StopSign"]
Crosswalk = _CLASSES["Crosswalk"]
SpeedBump = _CLASSES["SpeedBump"]
Driveway = _CLASSES["Driveway"]
