"""The map a predictor drives on, built from a log's map features (any source).

    mmap = motion_map_of(log)            # lanes + polygons + road edges
    request = RolloutRequest(states, start_step, fixed_rows, mmap)

* lanes: ``LaneGraph.from_features`` with the loader's explicit lane successors where it stored them
  (Waymo Open Motion's ``exit_lanes``: ``data.common.lane_successors``), inferred from geometry otherwise
  (Argoverse 2, the synthetic world). A map without lanes gives an empty graph (predictors then replay
  the vehicles, see ``Rollout.replayed``), never an error.
* context: ``MapContext.from_features`` (drivable area, crosswalks, lane segments, road edges).
* road edges: ``[E, 2, 2]`` segments of the ``"road_edge"`` features, in their polyline order (the road on
  their left in Waymo Open Motion).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

from simsplat_core.data.common import lane_successors
from simsplat_core.motion.predictor import MotionMap
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.types import MapFeature, SceneLog

logger = logging.getLogger(__name__)


def motion_map_from_features(features: Sequence[MapFeature],
                             successors: dict[str, list[str]] | None = None) -> MotionMap:
    """The :class:`MotionMap` of ``features``; ``successors`` (lane id -> successor ids) when known."""
    features = tuple(features)
    lanes = LaneGraph.from_features(features, successors=successors)
    context = MapContext.from_features(features)
    if not len(lanes):
        logger.info("map without lanes (%d features): the lane graph is empty", len(features))
    return MotionMap(lanes=lanes, context=context, road_edges=context.road_edges)


def motion_map_of(log: SceneLog) -> MotionMap:
    """The :class:`MotionMap` of ``log``'s map features (module docstring).

    Raises:
        ValueError: the log's stored lane successors are not a JSON object (``data.common.lane_successors``).
    """
    return motion_map_from_features(log.map_features, lane_successors(log))


__all__ = ["motion_map_from_features", "motion_map_of"]
