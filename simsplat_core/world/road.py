"""Road network of the procedural world: one four-way intersection with multi-lane arms.

Geometry is described in *intersection-local* coordinates ``(u, v)``: the origin is the centre of the
intersection, ``+u`` points along the ego's approach direction (east), ``+v`` to its left (north).
World coordinates are local ones shifted by ``RoadLayout.center`` (no rotation: the ego starts on the
west arm heading east, and the world frame is the first ego pose).

The horizontal road (arms ``W`` and ``E``) carries ``lanes_h`` lanes per direction plus a kerbside
parking strip; the vertical road (arms ``N`` and ``S``) carries ``lanes_v`` lanes per direction.
Traffic is right-handed. Corners are rounded with radius ``corner_radius``. Each arm has a zebra
crosswalk right next to the junction and a stop line behind it across the inbound lanes.

``RoadLayout`` answers point queries (vectorised over ``[N, 2]`` arrays; the ``INTERSECTION`` region is
the road up to the four stop lines, crosswalks and kerb fillets included), exports ``MapFeature``s and
round-trips through JSON so it can be stored in ``SceneLog.metadata["road_layout"]``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np

from simsplat_core.types import MapFeature

#: Arm name -> outward unit direction in local coordinates.
ARM_DIRS: dict[str, tuple[float, float]] = {"E": (1.0, 0.0), "N": (0.0, 1.0), "W": (-1.0, 0.0), "S": (0.0, -1.0)}
ARMS: tuple[str, ...] = ("E", "N", "W", "S")

#: Region codes returned by ``RoadLayout.region``.
OFFROAD, SIDEWALK, TRAVEL, PARKING, INTERSECTION = 0, 1, 2, 3, 4
REGION_NAMES = {
    OFFROAD: "offroad",
    SIDEWALK: "sidewalk",
    TRAVEL: "travel",
    PARKING: "parking",
    INTERSECTION: "intersection",
}


def arm_dir(arm: str) -> np.ndarray:
    """``[2]`` outward unit direction of an arm."""
    return np.asarray(ARM_DIRS[arm], dtype=np.float64)


def arm_normal(arm: str) -> np.ndarray:
    """``[2]`` left normal of the outward direction; inbound lanes lie on this side."""
    d = arm_dir(arm)
    return np.array([-d[1], d[0]])


def left_of(arm: str) -> str:
    """Arm reached by turning left when arriving from ``arm``."""
    return ARMS[(ARMS.index(arm) + 3) % 4]


def right_of(arm: str) -> str:
    """Arm reached by turning right when arriving from ``arm``."""
    return ARMS[(ARMS.index(arm) + 1) % 4]


def opposite(arm: str) -> str:
    return ARMS[(ARMS.index(arm) + 2) % 4]


def _bezier(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, p3: np.ndarray, n: int) -> np.ndarray:
    t = np.linspace(0.0, 1.0, n)[:, None]
    return (1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * p1 + 3 * (1 - t) * t**2 * p2 + t**3 * p3


def target_arm(arm: str, turn: str) -> str:
    """Arm a vehicle leaves by after ``turn`` (``straight``/``left``/``right``) from ``arm``."""
    return {"straight": opposite, "left": left_of, "right": right_of}[turn](arm)


def target_lane(layout: RoadLayout, arm: str, lane: int, turn: str) -> int | None:
    """Outbound lane index for a manoeuvre, or ``None`` when the lane may not make it.

    Left turns leave from the innermost lane into the innermost lane, right turns from the outermost
    lane into the outermost lane; straight keeps the lane index.
    """
    out_arm = target_arm(arm, turn)
    if turn == "straight":
        return lane if lane < layout.lanes(out_arm) else None
    if turn == "left":
        return 0 if lane == 0 else None
    return layout.lanes(out_arm) - 1 if lane == layout.lanes(arm) - 1 else None


def connector_points(layout: RoadLayout, arm: str, lane: int, turn: str, n: int = 32) -> np.ndarray | None:
    """``[n, 2]`` world points of the junction connector from inbound ``lane`` of ``arm``, or ``None``.

    The connector runs from the inbound stop line to the outer edge of the exit arm's crosswalk.
    """
    out_lane = target_lane(layout, arm, lane, turn)
    if out_lane is None:
        return None
    out_arm = target_arm(arm, turn)
    d0, n0 = arm_dir(arm), arm_normal(arm)
    d1, n1 = arm_dir(out_arm), arm_normal(out_arm)
    p0 = d0 * layout.stopline_s(arm) + n0 * layout.lane_offset(arm, True, lane)
    p3 = d1 * layout.crosswalk_range(out_arm)[1] + n1 * layout.lane_offset(out_arm, False, out_lane)
    h0, h1 = -d0, d1
    if turn == "straight":
        pts = p0 + np.linspace(0.0, 1.0, n)[:, None] * (p3 - p0)
    else:
        # corner where the two lane lines meet: p0 + a*h0 == p3 - b*h1
        mat = np.stack([h0, h1], axis=1)
        a, b = np.linalg.solve(mat, p3 - p0)
        k = 0.5523
        pts = _bezier(p0, p0 + k * a * h0, p3 - k * b * h1, p3, n)
    return layout.to_world(pts)


def _arc(center: np.ndarray, radius: float, a0: float, a1: float, n: int = 9) -> np.ndarray:
    """``[n, 2]`` points on a circular arc from angle ``a0`` to ``a1`` (radians)."""
    ang = np.linspace(a0, a1, n)
    return center + radius * np.stack([np.cos(ang), np.sin(ang)], axis=1)


@dataclass(frozen=True)
class RoadLayout:
    """Parameters of the intersection; all lengths in metres.

    Attributes:
        center: ``(x, y)`` world position of the intersection centre.
        lanes_h, lane_w_h, parking_w_h: lanes per direction, lane width and kerbside parking strip
            width of the horizontal (W-E, ego) road.
        lanes_v, lane_w_v: lanes per direction and lane width of the vertical (S-N) road.
        sidewalk_w: sidewalk width.
        corner_radius: kerb fillet radius at the four corners.
        crosswalk_gap: distance from the junction box to the near edge of each crosswalk.
        crosswalk_w: crosswalk depth along the arm.
        stopline_gap: distance from the crosswalk's outer edge to the stop line.
        arm_length: length of each arm in the exported map (shading extends to infinity).
    """

    center: tuple[float, float] = (0.0, 0.0)
    lanes_h: int = 2
    lane_w_h: float = 3.5
    parking_w_h: float = 2.4
    lanes_v: int = 2
    lane_w_v: float = 3.5
    sidewalk_w: float = 3.5
    corner_radius: float = 4.0
    crosswalk_gap: float = 0.8
    crosswalk_w: float = 3.0
    stopline_gap: float = 1.2
    arm_length: float = 90.0

    # ------------------------------------------------------------------ derived sizes
    @property
    def hw_h(self) -> float:
        """Half width of the horizontal road (kerb to centre line)."""
        return self.lanes_h * self.lane_w_h + self.parking_w_h

    @property
    def hw_v(self) -> float:
        """Half width of the vertical road."""
        return self.lanes_v * self.lane_w_v

    def is_horizontal(self, arm: str) -> bool:
        return arm in ("E", "W")

    def lanes(self, arm: str) -> int:
        return self.lanes_h if self.is_horizontal(arm) else self.lanes_v

    def lane_w(self, arm: str) -> float:
        return self.lane_w_h if self.is_horizontal(arm) else self.lane_w_v

    def half_width(self, arm: str) -> float:
        """Half width of the road an arm belongs to."""
        return self.hw_h if self.is_horizontal(arm) else self.hw_v

    def travel_half_width(self, arm: str) -> float:
        """Half width covered by travel lanes (parking strip excluded)."""
        return self.lanes(arm) * self.lane_w(arm)

    def junction_half(self, arm: str) -> float:
        """Distance from the centre to where an arm starts (half width of the crossing road)."""
        return self.hw_v if self.is_horizontal(arm) else self.hw_h

    def crosswalk_range(self, arm: str) -> tuple[float, float]:
        """Along-arm ``(start, end)`` of an arm's crosswalk."""
        s0 = self.junction_half(arm) + self.crosswalk_gap
        return s0, s0 + self.crosswalk_w

    def stopline_s(self, arm: str) -> float:
        """Along-arm position of an arm's stop line (its junction-side edge)."""
        return self.crosswalk_range(arm)[1] + self.stopline_gap

    def lane_offset(self, arm: str, inbound: bool, lane: int) -> float:
        """Signed lateral offset along ``arm_normal(arm)`` of a lane centre; lane 0 is next to the centre line."""
        off = (lane + 0.5) * self.lane_w(arm)
        return off if inbound else -off

    def parking_offset(self, arm: str, inbound: bool) -> float:
        """Signed lateral offset of the parking strip centre (horizontal arms only)."""
        off = self.travel_half_width(arm) + self.parking_w_h / 2.0 if self.is_horizontal(arm) else self.hw_v
        return off if inbound else -off

    # ------------------------------------------------------------------ frames
    def to_local(self, xy: np.ndarray) -> np.ndarray:
        """``[..., 2]`` world xy -> intersection-local uv."""
        return np.asarray(xy, dtype=np.float64)[..., :2] - np.asarray(self.center)

    def to_world(self, uv: np.ndarray) -> np.ndarray:
        """``[..., 2]`` intersection-local uv -> world xy."""
        return np.asarray(uv, dtype=np.float64) + np.asarray(self.center)

    def arm_point(self, arm: str, s: float, lateral: float) -> np.ndarray:
        """``[2]`` world point at along-arm distance ``s`` and lateral offset ``lateral``."""
        return self.to_world(arm_dir(arm) * s + arm_normal(arm) * lateral)

    # ------------------------------------------------------------------ point queries (local uv)
    def _road_mask_local(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        au, av = np.abs(u), np.abs(v)
        cross = (au <= self.hw_v) | (av <= self.hw_h)
        r = self.corner_radius
        fillet = (
            (au <= self.hw_v + r) & (av <= self.hw_h + r) & (np.hypot(au - (self.hw_v + r), av - (self.hw_h + r)) >= r)
        )
        return cross | fillet

    def region(self, xy: np.ndarray) -> np.ndarray:
        """Region code (``OFFROAD``/``SIDEWALK``/``TRAVEL``/``PARKING``/``INTERSECTION``) of ``[N, 2]`` world points."""
        uv = self.to_local(np.atleast_2d(xy))
        u, v = uv[:, 0], uv[:, 1]
        au, av = np.abs(u), np.abs(v)
        out = np.full(u.shape, OFFROAD, dtype=np.int64)
        road = self._road_mask_local(u, v)
        side = ~road & ((au <= self.hw_v + self.sidewalk_w) | (av <= self.hw_h + self.sidewalk_w))
        out[side] = SIDEWALK
        # the junction zone reaches out to the stop lines (crosswalks included) and covers the fillets
        zone = (au <= self.stopline_s("E")) & (av <= self.stopline_s("N"))
        junction = road & (zone | ((au > self.hw_v) & (av > self.hw_h)))
        on_h = road & ~junction & (av <= self.hw_h)
        on_v = road & ~junction & (au <= self.hw_v)
        out[on_h] = np.where(av[on_h] <= self.lanes_h * self.lane_w_h, TRAVEL, PARKING)
        out[on_v] = TRAVEL
        out[junction] = INTERSECTION
        return out

    def on_road(self, xy: np.ndarray) -> np.ndarray:
        """``[N]`` bool: inside the drivable area."""
        uv = self.to_local(np.atleast_2d(xy))
        return self._road_mask_local(uv[:, 0], uv[:, 1])

    def in_crosswalk(self, xy: np.ndarray) -> np.ndarray:
        """``[N]`` bool: inside one of the four crosswalk rectangles."""
        uv = self.to_local(np.atleast_2d(xy))
        out = np.zeros(uv.shape[0], dtype=bool)
        for arm in ARMS:
            s = uv @ arm_dir(arm)
            lat = uv @ arm_normal(arm)
            s0, s1 = self.crosswalk_range(arm)
            out |= (s >= s0) & (s <= s1) & (np.abs(lat) <= self.half_width(arm))
        return out

    def in_junction(self, xy: np.ndarray) -> np.ndarray:
        """``[N]`` bool: inside the junction zone (road up to the four stop lines, crosswalks and fillets included)."""
        return self.region(xy) == INTERSECTION

    # ------------------------------------------------------------------ map export
    def _corner_arc(self, su: float, sv: float, radius_extra: float = 0.0, n: int = 9) -> np.ndarray:
        """Kerb fillet of quadrant ``(su, sv)`` from the horizontal road edge to the vertical one (local)."""
        r = self.corner_radius
        c = np.array([su * (self.hw_v + r), sv * (self.hw_h + r)])
        a_h = np.arctan2(-sv, 0.0)  # point on the horizontal road edge
        a_v = np.arctan2(0.0, -su)  # point on the vertical road edge
        # go the short way round (90 degrees)
        diff = (a_v - a_h + np.pi) % (2 * np.pi) - np.pi
        return _arc(c, r + radius_extra, a_h, a_h + diff, n)

    def drivable_polygon(self) -> np.ndarray:
        """``[P, 2]`` world polygon of the drivable area (cross with rounded corners)."""
        L, hv, hh = self.arm_length, self.hw_v, self.hw_h
        pts: list[np.ndarray] = []
        # counter-clockwise, starting at the end of the east arm
        for su, sv in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
            arc = self._corner_arc(su, sv)
            # order each corner so the polygon runs counter-clockwise
            h_end = np.array([[su * L, sv * hh]])
            v_end = np.array([[su * hv, sv * L]])
            if su * sv > 0:
                pts += [h_end, arc, v_end]
            else:
                pts += [v_end, arc[::-1], h_end]
        return self.to_world(np.concatenate(pts, axis=0))

    def map_features(self) -> tuple[MapFeature, ...]:
        """All map features in world coordinates (z = 0)."""
        feats: list[MapFeature] = []

        def add(fid: str, kind: str, xy: np.ndarray) -> None:
            xy = np.asarray(xy, dtype=np.float64)
            feats.append(MapFeature(fid, kind, np.concatenate([xy, np.zeros((len(xy), 1))], axis=1)))

        L = self.arm_length
        for arm in ARMS:
            d, n = arm_dir(arm), arm_normal(arm)
            j = self.junction_half(arm)
            s_line = np.linspace(j, L, 12)
            for inbound in (True, False):
                for lane in range(self.lanes(arm)):
                    off = self.lane_offset(arm, inbound, lane)
                    pts = d * s_line[:, None] + n * off
                    if inbound:
                        pts = pts[::-1]  # lanes point in the direction of travel
                    add(f"lane_{arm}_{'in' if inbound else 'out'}_{lane}", "lane", self.to_world(pts))
            # markings: centre line, lane dividers, parking edge, stop line
            add(f"marking_{arm}_center", "lane_marking", self.to_world(d * s_line[[0, -1], None]))
            for inbound in (True, False):
                sign = 1.0 if inbound else -1.0
                for k in range(1, self.lanes(arm)):
                    off = sign * k * self.lane_w(arm)
                    add(
                        f"marking_{arm}_{'in' if inbound else 'out'}_divider_{k}",
                        "lane_marking",
                        self.to_world(d * s_line[[0, -1], None] + n * off),
                    )
                if self.is_horizontal(arm) and self.parking_w_h > 0:
                    off = sign * self.travel_half_width(arm)
                    add(
                        f"marking_{arm}_{'in' if inbound else 'out'}_parking_edge",
                        "lane_marking",
                        self.to_world(d * s_line[[0, -1], None] + n * off),
                    )
            s_stop = self.stopline_s(arm)
            add(
                f"marking_{arm}_stop_line",
                "lane_marking",
                self.to_world(np.stack([d * s_stop, d * s_stop + n * self.travel_half_width(arm)])),
            )
            s0, s1 = self.crosswalk_range(arm)
            hw = self.half_width(arm)
            quad = np.stack([d * s0 - n * hw, d * s1 - n * hw, d * s1 + n * hw, d * s0 + n * hw])
            add(f"crosswalk_{arm}", "crosswalk", self.to_world(quad))
        # connectors through the junction
        for arm in ARMS:
            for turn in ("straight", "left", "right"):
                for lane in range(self.lanes(arm)):
                    connector = connector_points(self, arm, lane, turn)
                    if connector is not None:
                        add(f"lane_conn_{arm}{lane}_{turn}", "lane", connector)
        # kerbs and sidewalks per quadrant
        sw = self.sidewalk_w
        for su, sv, name in ((1, 1, "NE"), (-1, 1, "NW"), (-1, -1, "SW"), (1, -1, "SE")):
            arc = self._corner_arc(su, sv)
            edge = np.concatenate(
                [np.array([[su * L, sv * self.hw_h]]), arc, np.array([[su * self.hw_v, sv * L]])], axis=0
            )
            add(f"road_edge_{name}", "road_edge", self.to_world(edge))
            outer = np.array(
                [
                    [su * self.hw_v + su * sw, sv * L],
                    [su * (self.hw_v + sw), sv * (self.hw_h + sw)],
                    [su * L, sv * (self.hw_h + sw)],
                ]
            )
            add(f"sidewalk_{name}", "sidewalk", self.to_world(np.concatenate([edge, outer], axis=0)))
        add("drivable_area", "drivable_area", self.drivable_polygon())
        return tuple(feats)

    # ------------------------------------------------------------------ serialisation
    def to_json(self) -> str:
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> RoadLayout:
        data = json.loads(text)
        data["center"] = tuple(data["center"])
        return cls(**data)


def sample_layout(rng: np.random.Generator) -> RoadLayout:
    """A randomised layout centred at the origin (``center`` is set once the ego start is known)."""
    return RoadLayout(
        lanes_h=2,
        lane_w_h=float(rng.uniform(3.3, 3.8)),
        parking_w_h=float(rng.uniform(2.3, 2.7)),
        lanes_v=int(rng.choice([1, 2], p=[0.35, 0.65])),
        lane_w_v=float(rng.uniform(3.2, 3.7)),
        sidewalk_w=float(rng.uniform(3.0, 4.5)),
        corner_radius=float(rng.uniform(3.0, 5.5)),
        crosswalk_gap=float(rng.uniform(0.5, 1.5)),
        crosswalk_w=float(rng.uniform(2.8, 3.8)),
        stopline_gap=float(rng.uniform(1.0, 2.0)),
    )
