"""The records of a scene's grounded facts: :class:`SceneFacts` and its agents, road and assets.

``mining.scene_facts`` computes them from an edit context; ``mining.vlm_protocol``'s ``SceneSummary`` carries
them next to their text lines for clients that reason on values. Plain frozen dataclasses of floats, strings
and tuples: distances are metres, speeds m/s, angles degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Areas an agent can be in (:attr:`AgentFacts.area`).
AREAS: tuple[str, ...] = ("ego_lane", "left_lane", "right_lane", "oncoming_lane", "other_lane", "intersection",
                          "crosswalk", "sidewalk", "road", "off_road")
#: Heading difference (degrees) beyond which a vehicle is oncoming.
ONCOMING_DEG = 135.0


@dataclass(frozen=True)
class AgentFacts:
    """One object of the scene (``mining.scene_facts`` module docstring).

    Attributes:
        object_id, node_id: the log's object and its scene-graph node.
        category: the log's category (``vehicle``, ``pedestrian``, ``cyclist``, ``static``, ``sign``, ...).
        kind: ``"vehicle"``, ``"pedestrian"`` or ``"static"`` (what can be done with it).
        caption: "a white SUV" ("" without a caption); subtype: "SUV", "adult", "traffic cone";
            color: main colour word ("" unknown).
        motion, sector, context: grounded labels (``scenario.vocabulary`` names; "" when the scene has none).
        moving: mean speed over the log above ``scene_facts.MOVING_MPS``; speed_mps: that mean speed.
        ahead_m, left_m: position in the ego frame at ``frame`` (metres ahead, to the left).
        heading_deg: heading relative to the ego's at ``frame``, in ``(-180, 180]`` (counter-clockwise).
        relation: ``vocabulary`` sector of the position at ``frame`` (``IN_FRONT_OF_EGO``, ...).
        area: one of :data:`AREAS` at ``frame``.
        lane_change_sides: sides (``"left"``, ``"right"``) with a same-direction lane next to its lane (vehicles).
        turns: turns (``"left"``, ``"right"``) whose intersection it reaches halfway before the log ends at its
            mean speed (moving vehicles).
        room_ahead_m, room_behind_m: free distance in its direction of travel to the nearest other agent at any
            step (bumper to bumper, ``inf`` when clear; vehicles).
        visible_share: share of the log's frames in which a camera sees it.
        frame: the frame the position refers to.
    """

    object_id: str
    node_id: int
    category: str
    kind: str
    caption: str
    subtype: str
    color: str
    motion: str
    sector: str
    context: str
    moving: bool
    speed_mps: float
    ahead_m: float
    left_m: float
    heading_deg: float
    relation: str
    area: str
    lane_change_sides: tuple[str, ...] = ()
    turns: tuple[str, ...] = ()
    room_ahead_m: float = math.inf
    room_behind_m: float = math.inf
    visible_share: float = 0.0
    frame: int = 0

    @property
    def distance_m(self) -> float:
        return math.hypot(self.ahead_m, self.left_m)

    @property
    def oncoming(self) -> bool:
        return abs(self.heading_deg) >= ONCOMING_DEG


@dataclass(frozen=True)
class RoadFacts:
    """The road ahead of the ego at the reference frame (``mining.scene_facts`` module docstring).

    Attributes:
        ego_speed_mps: the ego's mean speed over the log.
        lane_ahead_m: length of the ego's lane path ahead (0: the ego is on no lane), at most
            ``scene_facts.ROAD_LOOKAHEAD_M``.
        crosswalk_ahead_m, intersection_ahead_m: where the first crosswalk / intersection along it starts
            (``None``: none within ``lane_ahead_m``).
        plain_road: ``(start, end)`` stretches ahead (metres along the ego's lanes) on the road and off crosswalks
            and intersections.
        left_lane, right_lane: a same-direction lane next to the ego's.
        lanes_our_way, lanes_oncoming: lanes beside the ego at the reference pose, each way.
        sidewalks: the map has sidewalks.
        duration_s: length of the log.
    """

    ego_speed_mps: float = 0.0
    lane_ahead_m: float = 0.0
    crosswalk_ahead_m: float | None = None
    intersection_ahead_m: float | None = None
    plain_road: tuple[tuple[float, float], ...] = ()
    left_lane: bool = False
    right_lane: bool = False
    lanes_our_way: int = 0
    lanes_oncoming: int = 0
    sidewalks: bool = False
    duration_s: float = 0.0

    def plain_road_within(self, lo: float, hi: float, margin: float = 3.0) -> tuple[tuple[float, float], ...]:
        """The :attr:`plain_road` stretches clipped to ``[lo, hi]`` and shrunk by ``margin`` at each end (empty
        ones dropped)."""
        out = []
        for a, b in self.plain_road:
            a, b = max(a + margin, lo), min(b - margin, hi)
            if b >= a:
                out.append((a, b))
        return tuple(out)


@dataclass(frozen=True)
class AssetFacts:
    """One asset of the bank that inserts and replacements can use (category, subtype, colour, caption)."""

    category: str
    subtype: str
    color: str
    caption: str


@dataclass(frozen=True)
class SceneFacts:
    """Everything :func:`~simsplat_core.mining.scene_facts.scene_facts` found about one scene."""

    seq_id: str
    agents: tuple[AgentFacts, ...]
    road: RoadFacts
    assets: tuple[AssetFacts, ...] = ()

    def agent(self, object_id: str) -> AgentFacts:
        """The facts of ``object_id``. Raises ``KeyError`` naming it."""
        for a in self.agents:
            if a.object_id == object_id:
                return a
        raise KeyError(f"{self.seq_id}: no agent {object_id!r} in the scene facts")

    def of_kind(self, kind: str) -> tuple[AgentFacts, ...]:
        return tuple(a for a in self.agents if a.kind == kind)

    def assets_of(self, category: str) -> tuple[AssetFacts, ...]:
        return tuple(a for a in self.assets if a.category == category)


__all__ = ["AREAS", "ONCOMING_DEG", "AgentFacts", "AssetFacts", "RoadFacts", "SceneFacts"]
