"""Per-frame ground truth of search queries from what the synthetic world scripted, not from the search code.

Facts per agent come from the log that ``world.generate.generate_log`` wrote: the scripted behaviour
(``Motion.behavior``, stored as the object's ``behavior`` attribute), subtype and colour attributes, the
true boxes per frame (centre, heading, speed of the sampled path and speed profile) and the road layout
(``world.road.RoadLayout`` from the log's metadata: junction, crosswalk and road areas). Definitions
(``PHASES``), per frame of an agent with the named behaviour:

* ``turn``: inside the junction (``RoadLayout.in_junction``) and moving (> 0.5 m/s): where a scripted turn
  bends;
* ``lane_change``: heading more than 2 degrees off the nearest road axis (the layout's roads are axis-aligned
  in its local frame), i.e. the sideways part of the scripted change;
* ``decelerate``: the scripted speed profile is braking (d speed / dt < -0.5 m/s^2);
* ``still``: speed below 0.2 m/s (parked, waiting, standing; a scripted stop once it has stopped);
* ``cross``: on the road (``RoadLayout.on_road``) and moving (> 0.3 m/s);
* ``move``: speed above 0.5 m/s; ``any``: every frame.

Places: ``crosswalk`` / ``junction`` / ``road`` / ``sidewalk`` (off the road) from the layout; sectors from the
true centre in the ego frame (45-degree sectors: what "in front of ego" means in a query); the ego lane: within
1.75 m sideways of the ego's own route ahead (its true positions of the coming frames, then straight on from
the last one), at most 40 m along it and ahead of the ego: through a turn the lane bends with the route (a
straight box ahead of the ego would sweep over the oncoming lane). Relations: *following* = the other agent
ahead within 30 m along the agent's true heading, within 2 m sideways, headings within 30 degrees, both moving.

The ego is an agent too (category ``"ego"``): its scripted behaviour is the route's turn of the log's
``ego_route`` metadata (``turn_left`` / ``turn_right`` / ``straight``; the synthetic ego never stops), its
states the true ego poses. *Cut-in*: a scripted lane change, ahead of the ego within 30 m along its route,
within 4.5 m of the route sideways and closing in on it faster than 0.3 m/s. *Count*: at least ``count``
agents hold at once; ``together``: each within 3 m of another of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import invert_transform, wrap_angle
from simsplat_core.types import SceneLog
from simsplat_core.world.generate import layout_from_log

PHASES = ("turn", "lane_change", "decelerate", "still", "cross", "move", "any")


@dataclass(frozen=True)
class AgentSpec:
    """What a ground-truth agent is: attribute filters, scripted behaviours, the phase and place per frame.

    ``subtypes`` / ``colors`` / ``behaviors`` empty = any; ``categories`` the log categories allowed.
    """

    categories: tuple[str, ...] = ("vehicle",)
    subtypes: tuple[str, ...] = ()
    colors: tuple[str, ...] = ()
    behaviors: tuple[str, ...] = ()
    phase: str = "any"
    place: str = ""
    sector: str = ""
    in_ego_lane: bool = False
    following: AgentSpec | None = None
    cut_in: bool = False
    count: int = 1
    together: bool = False


@dataclass(frozen=True)
class WorldAgents:
    """True per-frame state of a log's movable agents: ``xy`` ``[O, F, 2]``, ``heading`` / ``speed`` ``[O, F]``, and the
    ego frame ``xy_ego`` ``[O, F, 2]``; attributes per agent."""

    object_ids: tuple[str, ...]
    attrs: tuple[dict[str, str], ...]
    categories: tuple[str, ...]
    xy: np.ndarray
    xy_ego: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    in_junction: np.ndarray
    in_crosswalk: np.ndarray
    on_road: np.ndarray
    fps: float
    route_lateral: np.ndarray
    route_along: np.ndarray

    @classmethod
    def from_log(cls, log: SceneLog) -> WorldAgents:
        layout = layout_from_log(log)
        objs = [o for o in log.objects if o.category in ("vehicle", "pedestrian", "cyclist")]
        F = log.num_frames
        dt = np.diff(log.timestamps_us).mean() * 1e-6 if F > 1 else 0.1
        ego_xy = log.ego_poses[:, :2, 3]
        ego_heading = np.unwrap(np.arctan2(log.ego_poses[:, 1, 0], log.ego_poses[:, 0, 0]))
        ego_speed = np.r_[np.linalg.norm(np.diff(ego_xy, axis=0), axis=1), 0.0] / dt
        ego_speed[-1] = ego_speed[-2] if F > 1 else 0.0
        turn = log.metadata.get("ego_route", "").split(" ")[-1]
        ego_attrs = {"behavior": {"left": "turn_left", "right": "turn_right"}.get(turn, "straight")}
        xy = np.stack([log.track(o.object_id).center[:, :2] for o in objs] + [ego_xy])  # [O+1, F, 2], ego last
        inv = np.stack([invert_transform(p) for p in log.ego_poses])  # [F, 4, 4]
        xy_ego = np.einsum("fij,ofj->ofi", inv[:, :2, :2], xy) + inv[None, :, :2, 3]
        flat = xy.reshape(-1, 2)
        shape = (len(objs) + 1, F)
        along, lateral = _route_coordinates(xy, ego_xy, ego_heading)
        return cls(tuple(o.object_id for o in objs) + ("ego",), tuple(dict(o.attributes) for o in objs) + (ego_attrs,),
                   tuple(o.category for o in objs) + ("ego",), xy, xy_ego,
                   np.stack([log.track(o.object_id).heading for o in objs] + [ego_heading]),
                   np.stack([log.track(o.object_id).speed for o in objs] + [ego_speed]),
                   layout.in_junction(flat).reshape(shape), layout.in_crosswalk(flat).reshape(shape),
                   layout.on_road(flat).reshape(shape), 1.0 / dt, lateral, along)


def _route_coordinates(xy: np.ndarray, ego_xy: np.ndarray, ego_heading: np.ndarray,
                       ahead_m: float = 40.0) -> tuple[np.ndarray, np.ndarray]:
    """``(along, lateral)`` ``[O, F]`` of agents ``xy`` ``[O, F, 2]`` against the ego's route ahead of each frame:
    the route is sampled at the ego's future positions, then every 0.5 m straight on from the last one; an agent
    is placed at its nearest route sample within ``ahead_m`` (``along``: metres of route to it, negative when
    behind the ego; ``lateral``: metres sideways of it in that sample's heading; ``nan`` where no sample)."""
    n, F = xy.shape[:2]
    along = np.full((n, F), np.nan)
    lateral = np.full((n, F), np.nan)
    ext = np.arange(0.5, ahead_m + 0.5, 0.5)
    h_last = ego_heading[-1]
    tail = ego_xy[-1] + ext[:, None] * np.array([np.cos(h_last), np.sin(h_last)])
    for f in range(F):
        pts = np.r_[ego_xy[f:], tail]
        heads = np.r_[ego_heading[f:], np.full(len(ext), h_last)]
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
        keep = s <= ahead_m
        pts, heads, s = pts[keep], heads[keep], s[keep]
        d = xy[:, f, None, :] - pts[None]  # [O, K, 2]
        k = np.argmin(np.linalg.norm(d, axis=-1), axis=1)
        dk = d[np.arange(n), k]
        c, sn = np.cos(heads[k]), np.sin(heads[k])
        along[:, f] = s[k] + dk[:, 0] * c + dk[:, 1] * sn
        lateral[:, f] = -dk[:, 0] * sn + dk[:, 1] * c
    return along, lateral


def _phase(w: WorldAgents, i: int, phase: str) -> np.ndarray:
    v = w.speed[i]
    if phase == "turn":
        return w.in_junction[i] & (v > 0.5)
    if phase == "lane_change":
        off_axis = np.abs(wrap_angle(w.heading[i] - np.round(w.heading[i] / (np.pi / 2)) * (np.pi / 2)))
        return np.rad2deg(off_axis) > 2.0
    if phase == "decelerate":
        return np.gradient(v) * w.fps < -0.5
    if phase == "still":
        return v < 0.2
    if phase == "cross":
        return w.on_road[i] & (v > 0.3)
    if phase == "move":
        return v > 0.5
    if phase == "any":
        return np.ones_like(v, dtype=bool)
    raise ValueError(f"unknown phase {phase!r} (one of {PHASES})")


def _place(w: WorldAgents, i: int, place: str) -> np.ndarray:
    places = {"": np.ones(w.speed.shape[1], dtype=bool), "crosswalk": w.in_crosswalk[i], "junction": w.in_junction[i],
              "road": w.on_road[i], "sidewalk": ~w.on_road[i]}
    return places.get(place, np.zeros(w.speed.shape[1], dtype=bool))  # a place the world has none of


def _sector(w: WorldAgents, i: int, sector: str) -> np.ndarray:
    ang = np.rad2deg(np.arctan2(w.xy_ego[i, :, 1], w.xy_ego[i, :, 0]))
    return {"": np.ones_like(ang, dtype=bool), "front": np.abs(ang) <= 45, "behind": np.abs(ang) >= 135,
            "left": (ang > 45) & (ang < 135), "right": (ang < -45) & (ang > -135)}[sector]


def _selected(w: WorldAgents, i: int, spec: AgentSpec) -> bool:
    a = w.attrs[i]
    return (w.categories[i] in spec.categories and (not spec.subtypes or a.get("subtype") in spec.subtypes)
            and (not spec.colors or a.get("color") in spec.colors)
            and (not spec.behaviors or a.get("behavior") in spec.behaviors))


def agent_truth(w: WorldAgents, spec: AgentSpec) -> np.ndarray:
    """``[O, F]`` bool: agent ``o`` is what ``spec`` describes at frame ``f`` (module docstring)."""
    out = np.zeros(w.speed.shape, dtype=bool)
    other = agent_truth(w, spec.following) if spec.following is not None else None
    for i in range(len(w.object_ids)):
        if not _selected(w, i, spec):
            continue
        ok = _phase(w, i, spec.phase) & _place(w, i, spec.place) & _sector(w, i, spec.sector)
        if spec.in_ego_lane:
            ok &= (w.route_along[i] > 0) & (w.route_along[i] < 40) & (np.abs(w.route_lateral[i]) < 1.75)
        if spec.cut_in:
            gap = np.abs(w.route_lateral[i])
            ok &= (w.route_along[i] > 0) & (w.route_along[i] < 30) & (gap < 4.5) & (np.gradient(gap) * w.fps < -0.3)
        if other is not None:
            c, s = np.cos(w.heading[i]), np.sin(w.heading[i])
            rel = np.zeros_like(ok)
            for j in np.flatnonzero(other.any(axis=1)):
                if j == i:
                    continue
                d = w.xy[j] - w.xy[i]
                along, lat = d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c
                dh = np.abs(np.rad2deg(wrap_angle(w.heading[j] - w.heading[i])))
                rel |= (other[j] & (along > 0) & (along < 30) & (np.abs(lat) < 2) & (dh < 30)
                        & (w.speed[i] > 0.5) & (w.speed[j] > 0.5))
            ok &= rel
        out[i] = ok
    return out


def query_truth(w: WorldAgents, specs: tuple[AgentSpec, ...]) -> np.ndarray:
    """``[F]`` bool: every spec holds for some agent in the frame."""
    out = np.ones(w.speed.shape[1], dtype=bool)
    for spec in specs:
        truth = agent_truth(w, spec)
        if spec.together:
            d = np.linalg.norm(w.xy[:, None] - w.xy[None], axis=-1)  # [O, O, F]
            near = (d < 3.0) & truth[:, None] & truth[None]
            near[np.arange(len(truth)), np.arange(len(truth))] = False
            truth &= near.any(axis=1)
        out &= truth.sum(axis=0) >= spec.count
    return out
