"""Agents of the procedural world and the seeded population step that places them.

``populate`` fills the scene around the ego's route with vehicles, pedestrians and static street
furniture. Candidates are drawn from behaviour recipes (``behaviors.py``) and accepted only when
their footprint never overlaps the ego or an already accepted agent at any frame, and when they come
into the cameras' rough field of view at least once. Every scene first receives two deliberate
look-alike pairs: two identical cars (one turning, one going straight) and two identically dressed
pedestrians (one crossing, one standing), so grounding must use motion and location.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.scenario.geometry import footprints_overlap
from simsplat_core.world import behaviors as bh
from simsplat_core.world.mesh import Mesh, PedestrianRig, pedestrian_extent, static_mesh, vehicle_mesh
from simsplat_core.world.palette import (
    HAIR_COLORS,
    LOOKALIKE_COLORS,
    LOOKALIKE_SUBTYPES,
    LOWER_COLORS,
    NAMED_COLORS,
    SKIN_TONES,
    STATIC_KINDS,
    UPPER_COLORS,
    VEHICLE_KIND_BY_NAME,
    VEHICLE_KINDS,
)
from simsplat_core.world.road import RoadLayout, arm_dir, arm_normal

logger = logging.getLogger(__name__)

EGO_SIZE = (4.8, 2.0, 1.6)
WALK_SWING = 0.45  # peak leg angle of walking pedestrians, radians


@dataclass
class Agent:
    """One non-ego object with its sampled trajectory.

    Attributes:
        category: ``vehicle``, ``pedestrian``, ``static`` or ``sign``.
        subtype: catalogue name (``sedan``, ``pedestrian``, ``traffic cone``, ...).
        size: box ``(length, width, height)``.
        motion: the intended motion.
        traj: sampled trajectory: ``xy [T, 2]``, ``heading [T]``, ``speed [T]``, ``s [T]``.
        appearance: colour facts (``color`` or ``upper_color``/``lower_color``).
        look: render parameters (RGB colours, pedestrian gait).
        lookalike_group: non-empty for members of a deliberate look-alike pair.
        object_id: assigned once the population is final.
    """

    category: str
    subtype: str
    size: tuple[float, float, float]
    motion: bh.Motion
    traj: dict[str, np.ndarray]
    appearance: dict[str, str]
    look: dict
    lookalike_group: str = ""
    object_id: str = ""
    _mesh: Mesh | None = field(default=None, repr=False)
    _rig: PedestrianRig | None = field(default=None, repr=False)

    @property
    def behavior(self) -> str:
        return self.motion.behavior

    def walk_phase(self, frame: int) -> float:
        """Gait phase (radians) of a pedestrian at ``frame``."""
        return float(self.look["phase0"] + 2 * np.pi * self.traj["s"][frame] / self.look["stride"])

    def local_mesh(self, frame: int) -> Mesh:
        """Mesh in the object frame at ``frame`` (rigid objects reuse one mesh)."""
        if self.category == "pedestrian":
            if self._rig is None:
                lk = self.look
                self._rig = PedestrianRig(self.size[2], lk["swing"], lk["upper"], lk["lower"], lk["skin"], lk["hair"])
            return self._rig.mesh(self.walk_phase(frame))
        if self._mesh is None:
            if self.category == "vehicle":
                self._mesh = vehicle_mesh(self.subtype, self.size, self.look["rgb"])
            else:
                self._mesh = static_mesh(self.subtype, self.size, self.look["rgb"])
        return self._mesh

    def world_mesh(self, frame: int) -> Mesh:
        """Mesh placed at the agent's pose in ``frame``."""
        h = float(self.traj["heading"][frame])
        c, s = np.cos(h), np.sin(h)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        x, y = self.traj["xy"][frame]
        return self.local_mesh(frame).transformed(rot, np.array([x, y, 0.0]))

    def footprint(self, frame: int) -> np.ndarray:
        """``[4, 2]`` counter-clockwise ground footprint at ``frame``."""
        h = float(self.traj["heading"][frame])
        L, W = self.size[0] / 2.0, self.size[1] / 2.0
        local = np.array([[L, W], [-L, W], [-L, -W], [L, -W]])
        c, s = np.cos(h), np.sin(h)
        return local @ np.array([[c, s], [-s, c]]) + self.traj["xy"][frame]


@dataclass(frozen=True)
class EgoPlan:
    """The ego's route: inbound lane of the west arm, manoeuvre, speed, time it reaches the stop line."""

    lane: int
    turn: str
    speed: float
    t_junction: float


def sample_ego_plan(layout: RoadLayout, rng: np.random.Generator) -> EgoPlan:
    turn = str(rng.choice(["straight", "left", "right"], p=[0.6, 0.2, 0.2]))
    if turn == "left":
        lane = 0
    elif turn == "right":
        lane = layout.lanes_h - 1
    else:
        lane = int(rng.integers(layout.lanes_h))
    if turn == "straight":
        return EgoPlan(lane, turn, float(rng.uniform(7.0, 10.0)), float(rng.uniform(1.2, 2.2)))
    return EgoPlan(lane, turn, float(rng.uniform(5.0, 6.5)), float(rng.uniform(0.5, 1.0)))


class Population:
    """Accumulates agents, rejecting candidates that collide or are never near the cameras."""

    def __init__(
        self,
        layout: RoadLayout,
        times: np.ndarray,
        ego_traj: dict[str, np.ndarray],
        plan: EgoPlan,
        rng: np.random.Generator,
    ) -> None:
        self.layout = layout
        self.times = times
        self.ego = ego_traj
        self.plan = plan
        self.rng = rng
        self.agents: list[Agent] = []

    # ---------------------------------------------------------------- acceptance
    def _margin(self, a: str, b: str) -> float:
        if "pedestrian" in (a, b):
            return 0.45 if ("vehicle" in (a, b)) else 0.2
        if a in ("static", "sign") or b in ("static", "sign"):
            return 0.3
        return 0.45

    def collides(self, cand: Agent) -> bool:
        xy, hd = cand.traj["xy"], cand.traj["heading"]
        size = cand.size[:2]
        if footprints_overlap(
            xy, hd, size, self.ego["xy"], self.ego["heading"], EGO_SIZE[:2], self._margin(cand.category, "vehicle")
        ).any():
            return True
        for other in self.agents:
            m = self._margin(cand.category, other.category)
            if footprints_overlap(xy, hd, size, other.traj["xy"], other.traj["heading"], other.size[:2], m).any():
                return True
        return False

    def near_cameras(self, cand: Agent, max_dist: float = 65.0) -> bool:
        rel = cand.traj["xy"] - self.ego["xy"]
        c, s = np.cos(self.ego["heading"]), np.sin(self.ego["heading"])
        xe = c * rel[:, 0] + s * rel[:, 1]
        ye = -s * rel[:, 0] + c * rel[:, 1]
        ang = np.abs(np.arctan2(ye, xe))
        return bool(np.any((xe > 1.0) & (np.hypot(xe, ye) < max_dist) & (ang < np.deg2rad(92.0))))

    def try_add(self, cand: Agent | None) -> bool:
        if cand is None or self.collides(cand) or not self.near_cameras(cand):
            return False
        self.agents.append(cand)
        return True

    def count(self, category: str) -> int:
        return sum(a.category in ((category,) if category != "static" else ("static", "sign")) for a in self.agents)

    # ---------------------------------------------------------------- builders
    def _sample(self, motion: bh.Motion) -> dict[str, np.ndarray]:
        return motion.sample(self.times)

    def vehicle(self, motion: bh.Motion, subtype: str, color: str, size=None, group: str = "") -> Agent:
        kind = VEHICLE_KIND_BY_NAME[subtype]
        if size is None:
            jit = 1.0 + self.rng.uniform(-0.03, 0.03)
            size = (kind.size[0] * jit, kind.size[1] * (1 + (jit - 1) / 2), kind.size[2] * jit)
        return Agent(
            "vehicle",
            subtype,
            (float(size[0]), float(size[1]), float(size[2])),
            motion,
            self._sample(motion),
            {"color": color},
            {"rgb": NAMED_COLORS[color]},
            group,
        )

    def pedestrian(self, motion: bh.Motion, upper: str, lower: str, height: float, group: str = "") -> Agent:
        walking = motion.behavior != "standing"
        swing = WALK_SWING if walking else 0.0
        size = pedestrian_extent(height, swing)
        look = {
            "upper": NAMED_COLORS[upper],
            "lower": NAMED_COLORS[lower],
            "skin": SKIN_TONES[int(self.rng.integers(len(SKIN_TONES)))],
            "hair": HAIR_COLORS[int(self.rng.integers(len(HAIR_COLORS)))],
            "swing": swing,
            "stride": 1.35 * height / 1.75,
            "phase0": float(self.rng.uniform(0, 2 * np.pi)),
        }
        return Agent(
            "pedestrian",
            "pedestrian",
            size,
            motion,
            self._sample(motion),
            {"upper_color": upper, "lower_color": lower},
            look,
            group,
        )

    def static(self, subtype: str, position: np.ndarray, heading: float, color: str | None = None) -> Agent:
        category, size, colors = STATIC_KINDS[subtype]
        color = color or colors[int(self.rng.integers(len(colors)))]
        motion = bh.static_at(position, heading)
        return Agent(
            category, subtype, size, motion, self._sample(motion), {"color": color}, {"rgb": NAMED_COLORS[color]}
        )

    # ---------------------------------------------------------------- vehicle recipes
    def vehicle_motion(self, recipe: str, length: float) -> bh.Motion | None:
        lay, rng, plan = self.layout, self.rng, self.plan
        u = rng.uniform
        nh, nv = lay.lanes_h, lay.lanes_v
        cross_arm = "N" if rng.random() < 0.5 else "S"
        if recipe == "oncoming_straight":
            return bh.drive(lay, "E", int(rng.integers(nh)), "straight", u(7.0, 11.0), u(-1.5, 3.5))
        if recipe == "oncoming_right":
            return bh.drive(lay, "E", nh - 1, "right", u(4.5, 6.5), u(-0.3, 1.0))
        if recipe == "oncoming_left":
            return bh.drive(lay, "E", 0, "left", u(4.5, 6.5), u(-0.3, 1.2))
        if recipe == "lead_straight":
            return bh.drive(lay, "W", int(rng.integers(nh)), "straight", u(6.0, 10.0), u(-3.5, plan.t_junction - 0.8))
        if recipe == "lead_left":
            return bh.drive(lay, "W", 0, "left", u(4.5, 6.5), u(-0.3, max(plan.t_junction - 1.0, 0.0)))
        if recipe == "lead_right":
            return bh.drive(lay, "W", nh - 1, "right", u(4.5, 6.5), u(-0.3, max(plan.t_junction - 1.0, 0.0)))
        if recipe == "cross_stop":
            return bh.stop_at_line(
                lay, cross_arm, int(rng.integers(nv)), u(6.0, 10.0), u(2.2, 3.5), u(0.0, 1.0), u(0.5, 1.5), length
            )
        if recipe == "cross_wait":
            slot = int(rng.choice([0, 0, 1, 2]))
            return bh.waiting(lay, cross_arm, int(rng.integers(nv)), u(0.5, 1.5) + slot * u(7.0, 8.0), length)
        if recipe == "cross_right":
            return bh.drive(lay, cross_arm, nv - 1, "right", u(4.0, 6.0), u(-0.8, 0.8))
        if recipe == "lane_change":
            if nh < 2:
                return None
            arm = "W" if rng.random() < 0.6 else "E"
            lane_from = int(rng.integers(nh))
            lane_to = lane_from + (1 if lane_from == 0 else -1)
            s_change = u(-35.0, 0.0) if arm == "W" else u(5.0, 35.0)
            return bh.change_lanes(lay, arm, lane_from, lane_to, u(7.0, 10.0), u(0.2, 1.2), u(18.0, 26.0), s_change)
        if recipe == "slow_down":
            if rng.random() < 0.6:
                return bh.slow_down(
                    lay,
                    "W",
                    int(rng.integers(nh)),
                    "straight",
                    u(7.0, 10.0),
                    u(-3.0, plan.t_junction - 1.0),
                    u(0.2, 1.2),
                    u(0.2, 0.45),
                )
            return bh.slow_down(
                lay, "E", int(rng.integers(nh)), "straight", u(7.0, 10.0), u(0.5, 4.0), u(0.2, 1.2), u(0.2, 0.45)
            )
        if recipe == "parked":
            arm = "W" if rng.random() < 0.6 else "E"
            s0 = lay.stopline_s(arm) + length / 2.0 + 5.0
            s1 = s0 + 40.0 if arm == "W" else s0 + 35.0
            return bh.parked(lay, arm, bool(rng.random() < 0.6), u(s0, s1))
        raise ValueError(f"unknown vehicle recipe {recipe!r}")

    def random_kind(self) -> str:
        weights = np.array([k.weight for k in VEHICLE_KINDS])
        return VEHICLE_KINDS[int(self.rng.choice(len(VEHICLE_KINDS), p=weights / weights.sum()))].subtype

    def random_color(self, subtype: str) -> str:
        colors = VEHICLE_KIND_BY_NAME[subtype].colors
        return colors[int(self.rng.integers(len(colors)))]


_RANDOM_RECIPES = {
    "parked": 2.2,
    "oncoming_straight": 2.0,
    "lead_straight": 1.5,
    "cross_stop": 1.5,
    "cross_wait": 1.5,
    "lane_change": 1.0,
    "slow_down": 1.0,
    "oncoming_right": 0.7,
    "lead_left": 0.5,
    "lead_right": 0.5,
    "cross_right": 0.7,
    "oncoming_left": 0.3,
}


def _heading_change(traj: dict[str, np.ndarray]) -> float:
    return float(np.rad2deg(abs(np.unwrap(traj["heading"])[-1] - np.unwrap(traj["heading"])[0])))


def _add_vehicle_lookalikes(pop: Population) -> None:
    rng = pop.rng
    subtype = LOOKALIKE_SUBTYPES[int(rng.integers(len(LOOKALIKE_SUBTYPES)))]
    color = LOOKALIKE_COLORS[int(rng.integers(len(LOOKALIKE_COLORS)))]
    size = VEHICLE_KIND_BY_NAME[subtype].size
    turning = ["oncoming_right", "lead_left", "lead_right", "cross_right", "oncoming_left"]
    best: Agent | None = None
    for _ in range(40):
        recipe = turning[int(rng.integers(len(turning)))]
        motion = pop.vehicle_motion(recipe, size[0])
        if motion is None:  # not on these roads (the pair's recipes always are)
            continue
        cand = pop.vehicle(motion, subtype, color, size, "vehicle_pair")
        if pop.collides(cand) or not pop.near_cameras(cand):
            continue
        if _heading_change(cand.traj) > 75.0:
            best = cand
            break
        if best is None or _heading_change(cand.traj) > _heading_change(best.traj):
            best = cand
    if best is not None:
        pop.agents.append(best)
    straight = ["oncoming_straight", "lead_straight", "parked"]
    for attempt in range(40):
        recipe = straight[int(rng.integers(len(straight)))] if attempt < 30 else "parked"
        motion = pop.vehicle_motion(recipe, size[0])
        if motion is None:
            continue
        cand = pop.vehicle(motion, subtype, color, size, "vehicle_pair")
        if _heading_change(cand.traj) < 10.0 and pop.try_add(cand):
            break


def _crossing_motion(pop: Population, arm: str) -> bh.Motion:
    lay, rng = pop.layout, pop.rng
    hw = lay.half_width(arm)
    to_left = bool(rng.random() < 0.5)
    speed = float(rng.uniform(1.1, 1.6))
    remaining = float(rng.uniform(0.3, 0.95)) * 2 * hw
    sign = 1.0 if to_left else -1.0
    lateral0 = sign * (hw - remaining)
    return bh.cross_street(lay, arm, to_left, lateral0, float(rng.uniform()), speed)


def _standing_spot(pop: Population, arm: str) -> tuple[np.ndarray, float]:
    lay, rng = pop.layout, pop.rng
    n = arm_normal(arm)
    cw0, cw1 = lay.crosswalk_range(arm)
    side = 1.0 if rng.random() < 0.5 else -1.0
    s = 0.5 * (cw0 + cw1) + rng.uniform(-1.5, 2.5)
    lat = side * (lay.half_width(arm) + rng.uniform(0.6, min(1.8, lay.sidewalk_w - 0.4)))
    pos = lay.arm_point(arm, s, lat)
    facing = -side * n
    heading = float(np.arctan2(facing[1], facing[0]) + rng.uniform(-0.4, 0.4))
    return pos, heading


def _add_pedestrian_lookalikes(pop: Population) -> None:
    rng = pop.rng
    upper = ("red", "yellow", "blue", "green", "white")[int(rng.integers(5))]
    lower = LOWER_COLORS[int(rng.integers(len(LOWER_COLORS)))]
    for _ in range(40):
        arm = "W" if rng.random() < 0.5 else "E"
        if pop.try_add(
            pop.pedestrian(_crossing_motion(pop, arm), upper, lower, float(rng.uniform(1.6, 1.9)), "pedestrian_pair")
        ):
            break
    for _ in range(40):
        arm = "W" if rng.random() < 0.5 else "E"
        pos, heading = _standing_spot(pop, arm)
        if pop.try_add(
            pop.pedestrian(bh.stand(pos, heading), upper, lower, float(rng.uniform(1.6, 1.9)), "pedestrian_pair")
        ):
            break


def _random_pedestrian(pop: Population) -> Agent:
    lay, rng = pop.layout, pop.rng
    upper = UPPER_COLORS[int(rng.integers(len(UPPER_COLORS)))]
    lower = LOWER_COLORS[int(rng.integers(len(LOWER_COLORS)))]
    height = float(rng.uniform(1.55, 1.92))
    kind = rng.choice(["walk", "walk", "cross", "stand"])
    if kind == "walk":
        arm = str(rng.choice(["W", "E", "N", "S"], p=[0.4, 0.3, 0.15, 0.15]))
        s0 = lay.junction_half(arm) + rng.uniform(lay.sidewalk_w + 1.0, 35.0)
        motion = bh.walk_sidewalk(
            lay,
            arm,
            bool(rng.random() < 0.5),
            s0,
            bool(rng.random() < 0.5),
            float(rng.uniform(1.0, 1.6)),
            float(rng.uniform()),
        )
    elif kind == "cross":
        motion = _crossing_motion(pop, str(rng.choice(["W", "E", "N", "S"], p=[0.3, 0.3, 0.2, 0.2])))
    else:
        arm = str(rng.choice(["W", "E", "N", "S"]))
        if rng.random() < 0.5:
            pos, heading = _standing_spot(pop, arm)
        else:
            side = 1.0 if rng.random() < 0.5 else -1.0
            s = lay.junction_half(arm) + rng.uniform(lay.sidewalk_w + 1.0, 30.0)
            pos = lay.arm_point(arm, s, side * (lay.half_width(arm) + rng.uniform(0.5, lay.sidewalk_w - 0.4)))
            heading = float(rng.uniform(-np.pi, np.pi))
        motion = bh.stand(pos, heading)
    return pop.pedestrian(motion, upper, lower, height)


def _add_statics(pop: Population, target: int) -> None:
    lay, rng = pop.layout, pop.rng
    added = 0
    # stop signs for the side streets, facing their approaching traffic
    for arm in ("N", "S"):
        if added >= target:
            return
        if rng.random() < 0.75:
            d = arm_dir(arm)
            pos = lay.arm_point(
                arm, lay.stopline_s(arm) + rng.uniform(0.3, 1.5), lay.half_width(arm) + rng.uniform(0.4, 0.8)
            )
            added += pop.try_add(pop.static("stop sign", pos, float(np.arctan2(d[1], d[0]))))
    # a speed limit or parking sign along the ego's road, facing the ego
    if added < target:
        arm = "W" if rng.random() < 0.6 else "E"
        inbound = arm == "W"
        side = 1.0 if inbound else -1.0
        subtype = "speed limit sign" if rng.random() < 0.6 else "parking sign"
        s = lay.stopline_s(arm) + rng.uniform(6.0, 30.0)
        pos = lay.arm_point(arm, s, side * (lay.half_width(arm) + rng.uniform(0.3, 0.7)))
        added += pop.try_add(pop.static(subtype, pos, np.pi))
    # a work zone: cones (and maybe a barrier) in a parking strip
    for _ in range(10):
        if added >= target:
            break
        arm = "W" if rng.random() < 0.55 else "E"
        inbound = bool(rng.random() < 0.5)
        off = lay.parking_offset(arm, inbound)
        s = lay.stopline_s(arm) + rng.uniform(4.0, 30.0)
        d = arm_dir(arm)
        heading = float(np.arctan2(d[1], d[0]))
        if rng.random() < 0.3:
            added += pop.try_add(pop.static("barrier", lay.arm_point(arm, s, off), heading))
            continue
        for k in range(int(rng.integers(2, 4))):
            if added >= target:
                break
            added += pop.try_add(
                pop.static("traffic cone", lay.arm_point(arm, s + 2.2 * k, off + rng.uniform(-0.3, 0.3)), heading)
            )


def populate(
    layout: RoadLayout,
    times: np.ndarray,
    ego_traj: dict[str, np.ndarray],
    plan: EgoPlan,
    rng: np.random.Generator,
    num_vehicles: tuple[int, int],
    num_pedestrians: tuple[int, int],
    num_static: tuple[int, int],
) -> list[Agent]:
    """Place vehicles, pedestrians and static objects; returns agents with ids assigned.

    Order of ids: vehicles ``veh_NN``, pedestrians ``ped_NN``, static objects ``static_NN`` / ``sign_NN``.
    """
    pop = Population(layout, times, ego_traj, plan, rng)
    n_veh = int(rng.integers(num_vehicles[0], num_vehicles[1] + 1))
    n_ped = int(rng.integers(num_pedestrians[0], num_pedestrians[1] + 1))
    n_static = int(rng.integers(num_static[0], num_static[1] + 1))
    if n_veh >= 2:
        _add_vehicle_lookalikes(pop)
    if n_ped >= 2:
        _add_pedestrian_lookalikes(pop)
    _add_statics(pop, n_static)
    names = list(_RANDOM_RECIPES)
    weights = np.array([_RANDOM_RECIPES[k] for k in names])
    for _ in range(15 * max(n_veh, 1)):
        if pop.count("vehicle") >= n_veh:
            break
        recipe = names[int(rng.choice(len(names), p=weights / weights.sum()))]
        subtype = pop.random_kind()
        if recipe == "parked" and subtype == "bus":
            subtype = "van"
        motion = pop.vehicle_motion(recipe, VEHICLE_KIND_BY_NAME[subtype].size[0])
        if motion is not None:
            pop.try_add(pop.vehicle(motion, subtype, pop.random_color(subtype)))
    for _ in range(15 * max(n_ped, 1)):
        if pop.count("pedestrian") >= n_ped:
            break
        pop.try_add(_random_pedestrian(pop))
    order = {"vehicle": 0, "pedestrian": 1, "static": 2, "sign": 2}
    agents = sorted(pop.agents, key=lambda a: order[a.category])  # stable: keeps insertion order
    prefix = {"vehicle": "veh", "pedestrian": "ped", "static": "static", "sign": "sign"}
    counters: dict[str, int] = {}
    for agent in agents:
        k = counters.get(agent.category, 0)
        counters[agent.category] = k + 1
        agent.object_id = f"{prefix[agent.category]}_{k:02d}"
    logger.debug(
        "placed %d vehicles, %d pedestrians, %d static objects",
        pop.count("vehicle"),
        pop.count("pedestrian"),
        pop.count("static"),
    )
    return agents
