"""``ExportScenario``: one scenario as every export format needs it, independent of any one format.

The exporters (``export.womd``, ``export.scenarionet``, ``export.parquet_tables``) read only this record, so a
new format is one module over it. It follows Waymo Open Motion's ``Scenario`` (the richest of the targets):
tracks as a dense ``[A, T]`` grid of box states with a validity mask, integer track and map-feature ids, the
SDC's track index, the tracks of interest and to predict, map features with lane connectivity, and traffic
signal states per step.

Frames and units: metres in the log's world frame (the SDC's pose at the log's first frame, z up), headings in
radians counter-clockwise from world +x, velocities in m/s in the world frame, time in seconds from the log's
first frame (``timestamps_s[0]`` need not be 0 for a window cut from a longer log).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

#: Columns of ``ExportScenario.states[..., k]``.
STATE_COLUMNS: tuple[str, ...] = (
    "center_x", "center_y", "center_z", "length", "width", "height", "heading", "velocity_x", "velocity_y",
)
X, Y, Z, LENGTH, WIDTH, HEIGHT, HEADING, VX, VY = range(len(STATE_COLUMNS))

#: Agent types of an exported scenario (WOMD's ``Track.ObjectType`` without the ``TYPE_`` prefix, lower case).
AGENT_TYPES: tuple[str, ...] = ("unset", "vehicle", "pedestrian", "cyclist", "other")

#: Kinds of exported map features (WOMD's ``MapFeature`` oneof members).
MAP_FEATURE_KINDS: tuple[str, ...] = (
    "lane", "road_line", "road_edge", "stop_sign", "crosswalk", "speed_bump", "driveway",
)
#: Polygon kinds (closed implicitly: the last point connects to the first).
POLYGON_KINDS: frozenset[str] = frozenset({"crosswalk", "speed_bump", "driveway"})

#: WOMD type names per map kind, in enum order (index = the proto enum value); ``""``: the kind has no type.
LANE_TYPES: tuple[str, ...] = ("TYPE_UNDEFINED", "TYPE_FREEWAY", "TYPE_SURFACE_STREET", "TYPE_BIKE_LANE")
ROAD_LINE_TYPES: tuple[str, ...] = (
    "TYPE_UNKNOWN", "TYPE_BROKEN_SINGLE_WHITE", "TYPE_SOLID_SINGLE_WHITE", "TYPE_SOLID_DOUBLE_WHITE",
    "TYPE_BROKEN_SINGLE_YELLOW", "TYPE_BROKEN_DOUBLE_YELLOW", "TYPE_SOLID_SINGLE_YELLOW",
    "TYPE_SOLID_DOUBLE_YELLOW", "TYPE_PASSING_DOUBLE_YELLOW",
)
ROAD_EDGE_TYPES: tuple[str, ...] = ("TYPE_UNKNOWN", "TYPE_ROAD_EDGE_BOUNDARY", "TYPE_ROAD_EDGE_MEDIAN")
#: Map kind -> its type names (kinds without a type are absent).
MAP_TYPES: dict[str, tuple[str, ...]] = {"lane": LANE_TYPES, "road_line": ROAD_LINE_TYPES, "road_edge": ROAD_EDGE_TYPES}

#: WOMD ``TrafficSignalLaneState.State`` names, in enum order.
SIGNAL_STATES: tuple[str, ...] = (
    "LANE_STATE_UNKNOWN", "LANE_STATE_ARROW_STOP", "LANE_STATE_ARROW_CAUTION", "LANE_STATE_ARROW_GO",
    "LANE_STATE_STOP", "LANE_STATE_CAUTION", "LANE_STATE_GO", "LANE_STATE_FLASHING_STOP",
    "LANE_STATE_FLASHING_CAUTION",
)

#: ``ExportScenario.track_sources`` values (the ``trajectories`` table's sources).
TRACK_SOURCES: tuple[str, ...] = ("log", "edited", "inserted", "refined")


@dataclass(frozen=True)
class ExportMapFeature:
    """One map feature.

    Attributes:
        feature_id: integer id, unique in the scenario (the source's where it had integers).
        kind: one of :data:`MAP_FEATURE_KINDS`.
        type: the WOMD type name of its kind (:data:`MAP_TYPES`; ``""`` for kinds without a type).
        points: ``[P, 3]`` float64 polyline (lanes, lines, edges), polygon (crosswalk, speed bump, driveway) or the
            one position of a stop sign.
        entry_lanes, exit_lanes: lane ids (lanes only).
        left_neighbors, right_neighbors: lane ids of the neighbours (lanes only).
        controlled_lanes: lane ids a stop sign controls (stop signs only).
        speed_limit_mph: lanes only; ``0.0`` when unknown.
        source_id: the feature's id in the stored log (``"lane_123"``), for the manifest's id mapping.
    """

    feature_id: int
    kind: str
    points: np.ndarray
    type: str = ""
    entry_lanes: tuple[int, ...] = ()
    exit_lanes: tuple[int, ...] = ()
    left_neighbors: tuple[int, ...] = ()
    right_neighbors: tuple[int, ...] = ()
    controlled_lanes: tuple[int, ...] = ()
    speed_limit_mph: float = 0.0
    source_id: str = ""

    def __post_init__(self) -> None:
        where = f"map feature {self.feature_id} ({self.source_id or self.kind})"
        if self.kind not in MAP_FEATURE_KINDS:
            raise ValueError(f"{where}: kind must be one of {list(MAP_FEATURE_KINDS)}, got {self.kind!r}")
        if self.type and self.type not in MAP_TYPES.get(self.kind, ()):
            known = list(MAP_TYPES.get(self.kind, ()))
            raise ValueError(f"{where}: type {self.type!r} is not a {self.kind} type {known}")
        pts = np.asarray(self.points)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
            raise ValueError(f"{where}: points must be [P>=1, 3], got {list(pts.shape)}")


@dataclass(frozen=True)
class SignalState:
    """The state of one lane's traffic signal at one step (WOMD ``TrafficSignalLaneState``).

    Attributes:
        lane_id: the controlled lane's feature id.
        state: one of :data:`SIGNAL_STATES`.
        stop_point: ``[3]`` where the lane's traffic stops, or ``None``.
    """

    lane_id: int
    state: str
    stop_point: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.state not in SIGNAL_STATES:
            raise ValueError(f"signal of lane {self.lane_id}: state must be one of {list(SIGNAL_STATES)}, "
                             f"got {self.state!r}")


@dataclass(frozen=True, eq=False)
class ExportScenario:
    """One scenario to export (module docstring). ``A`` tracks, ``T`` steps.

    Attributes:
        scenario_id: unique and deterministic (from sequence, edit, attempt and window).
        timestamps_s: ``[T]`` float64 seconds, increasing.
        current_time_index: the last step of the observed history.
        track_ids: ``[A]`` int64 ids, unique.
        agent_types: ``[A]`` one of :data:`AGENT_TYPES` each.
        states: ``[A, T, 9]`` float64 box states (:data:`STATE_COLUMNS`); rows of invalid steps are zeros.
        valid: ``[A, T]`` bool, the agent exists at that step.
        sdc_index: row of the self-driving car (the ego).
        objects_of_interest: track ids of the agents the scenario is about (the edited and inserted ones).
        tracks_to_predict: rows of the tracks a predictor must forecast (edited agents and those whose paths the
            refinement changed), each valid at ``current_time_index``.
        track_sources: ``[A]`` one of :data:`TRACK_SOURCES` each.
        source_object_ids: ``[A]`` each track's object id in the stored log or edit (``"ego"`` for the SDC).
        map_features: the map.
        signals: ``T`` tuples of the signal states at each step (empty tuples when the source had none).
        metadata: string facts about where it came from (sequence, log source, run, edit, prompt, window, what
            was resampled or padded): every format writes them where it has room.
    """

    scenario_id: str
    timestamps_s: np.ndarray
    current_time_index: int
    track_ids: np.ndarray
    agent_types: tuple[str, ...]
    states: np.ndarray
    valid: np.ndarray
    sdc_index: int
    objects_of_interest: tuple[int, ...] = ()
    tracks_to_predict: tuple[int, ...] = ()
    track_sources: tuple[str, ...] = ()
    source_object_ids: tuple[str, ...] = ()
    map_features: tuple[ExportMapFeature, ...] = ()
    signals: tuple[tuple[SignalState, ...], ...] = ()
    metadata: Mapping[str, str] = field(default_factory=dict)

    @property
    def num_tracks(self) -> int:
        return len(self.track_ids)

    @property
    def num_steps(self) -> int:
        return len(self.timestamps_s)

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise ``ValueError`` naming the scenario and the field when the record is inconsistent."""
        self._validate_grid()
        self._validate_tracks()
        self._validate_map()

    def _validate_grid(self) -> None:
        where = f"scenario {self.scenario_id!r}"
        a, t = self.num_tracks, self.num_steps
        if t == 0 or np.any(np.diff(self.timestamps_s) <= 0):
            raise ValueError(f"{where}: timestamps_s must be non-empty and increasing")
        if not 0 <= self.current_time_index < t:
            raise ValueError(f"{where}: current_time_index {self.current_time_index} is not a step of {t}")
        for name, shape in (("states", (a, t, len(STATE_COLUMNS))), ("valid", (a, t))):
            got = tuple(np.shape(getattr(self, name)))
            if got != shape:
                raise ValueError(f"{where}: {name} must be {list(shape)}, got {list(got)}")
        for name in ("agent_types", "track_sources", "source_object_ids"):
            value = getattr(self, name)
            if name != "agent_types" and not value:
                continue
            if len(value) != a:
                raise ValueError(f"{where}: {name} has {len(value)} entries for {a} tracks")

    def _validate_tracks(self) -> None:
        where = f"scenario {self.scenario_id!r}"
        a = self.num_tracks
        bad_types = sorted(set(self.agent_types) - set(AGENT_TYPES))
        if bad_types:
            raise ValueError(f"{where}: agent_types {bad_types} not in {list(AGENT_TYPES)}")
        bad_sources = sorted(set(self.track_sources) - set(TRACK_SOURCES))
        if bad_sources:
            raise ValueError(f"{where}: track_sources {bad_sources} not in {list(TRACK_SOURCES)}")
        if len(set(self.track_ids.tolist())) != a:
            raise ValueError(f"{where}: track_ids are not unique")
        if not 0 <= self.sdc_index < a:
            raise ValueError(f"{where}: sdc_index {self.sdc_index} is not a track row of {a}")
        unknown = sorted(set(self.objects_of_interest) - set(self.track_ids.tolist()))
        if unknown:
            raise ValueError(f"{where}: objects_of_interest {unknown} are not track ids")
        for row in self.tracks_to_predict:
            if not (0 <= row < a and self.valid[row, self.current_time_index]):
                raise ValueError(f"{where}: tracks_to_predict row {row} is not a track valid at the current step")

    def _validate_map(self) -> None:
        where = f"scenario {self.scenario_id!r}"
        t = self.num_steps
        if self.signals and len(self.signals) != t:
            raise ValueError(f"{where}: signals has {len(self.signals)} steps, timestamps {t}")
        ids = [f.feature_id for f in self.map_features]
        if len(set(ids)) != len(ids):
            raise ValueError(f"{where}: map feature ids are not unique")
