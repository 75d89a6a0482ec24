"""The scenario layer below language, editing and motion: what agents do and where, on any map.

* ``vocabulary`` -- motion classes per agent kind, location sectors and map contexts with their
  phrases, spelled once as named constants;
* ``trajectory`` -- object trajectories from logs: smoothed velocities, headings, ego frames;
* ``path`` -- arc-length parametrised paths;
* ``map_context`` -- point queries against a log's map (drivable area, crosswalks, inferred
  intersections, lane offsets);
* ``lane_graph`` -- a directed lane graph over ``MapFeature`` s of any source: successors,
  neighbours, nearest lane, lane-following paths through junctions;
* ``geometry`` -- polygons, oriented-box overlap, signed distances of box corners to the drivable area.

Used by ``world`` (behaviours, population), ``language`` (auto-labeller, grounding) and ``eval``.
Framework-free: numpy only.
"""
