"""Entry point of the procedural world: ``generate_log(seed, config) -> SceneLog``.

Pipeline: sample a road layout and the ego's route (all randomness from one
``numpy.random.Generator(PCG64(seed))``, drawn in a fixed order) -> place agents -> build the
scenery -> render every camera of every frame (RGB, z-depth, instance ids) -> derive visibility and
captions from the rendered masks and the sampled trajectories -> assemble and validate the log.
Identical seeds and configs give bit-identical logs.

``generate_world`` returns the intermediate ``World`` (layout, agents, meshes, rig) for callers and
tests that need more than the log, e.g. a pedestrian's mesh at a given frame.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import box_corners, pose_from_yaw, project_box_bounds
from simsplat_core.types import (
    SYNTHETIC_SOURCE,
    CameraImage,
    ObjectInfo,
    SceneLog,
    Track,
    node_type_for_category,
    split_for_frame,
)
from simsplat_core.world import behaviors as bh
from simsplat_core.world.agents import Agent, EgoPlan, populate, sample_ego_plan
from simsplat_core.world.captions import compose_caption, describe_appearance, describe_track
from simsplat_core.world.config import WORLD_VERSION, WorldConfig, default_seq_id
from simsplat_core.world.mesh import Mesh
from simsplat_core.world.render import (
    DrawList,
    Lighting,
    camera_intrinsics,
    camera_to_ego,
    render_view,
    silhouette_view,
)
from simsplat_core.world.road import RoadLayout, sample_layout
from simsplat_core.world.scenery import build_scenery

logger = logging.getLogger(__name__)


@dataclass
class World:
    """Everything generated for one seed before rendering.

    Attributes:
        seed, config: inputs.
        layout: road layout (world frame = first ego pose).
        plan: the ego's route.
        times: ``[F]`` seconds since the first frame.
        ego_poses: ``[F, 4, 4]`` ego-to-world, ``ego_poses[0]`` is the identity.
        ego_speed: ``[F]`` m/s.
        agents: placed objects (ids assigned); ``instance_id`` is the 1-based position.
        scenery: world-space background mesh (buildings, trees).
        lighting: sun/sky lighting.
        texture_seed: integer seed of the procedural textures.
    """

    seed: int
    config: WorldConfig
    layout: RoadLayout
    plan: EgoPlan
    times: np.ndarray
    ego_poses: np.ndarray
    ego_speed: np.ndarray
    agents: list[Agent]
    scenery: Mesh
    lighting: Lighting
    texture_seed: int

    def instance_id(self, agent: Agent) -> int:
        return self.agents.index(agent) + 1

    def camera_poses(self, frame: int) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """``(name, K [3, 3], cam_to_world [4, 4])`` of every camera at ``frame``."""
        cfg = self.config
        return [
            (spec.name, camera_intrinsics(spec, cfg.width, cfg.height), self.ego_poses[frame] @ camera_to_ego(spec))
            for spec in cfg.cameras
        ]

    def draw_list(self, frame: int) -> DrawList:
        """All triangles of ``frame`` (agents with their instance ids, scenery with 0)."""
        items = [(self.scenery, 0)] + [(a.world_mesh(frame), k + 1) for k, a in enumerate(self.agents)]
        return DrawList.build(items, self.lighting)

    def silhouette_pixels(self, frame: int, instance_ids: Sequence[int]) -> dict[str, np.ndarray]:
        """Per camera name, ``[N]`` int pixels each of ``instance_ids`` would cover at ``frame`` with nothing in
        front of it (``render.silhouette_view``; compare with ``render``'s instance map to tell how much of an
        object is hidden)."""
        draw = self.draw_list(frame)
        cfg = self.config
        return {name: np.asarray([int(silhouette_view(draw, int(i), K, c2w, cfg.width, cfg.height).sum())
                                  for i in instance_ids], dtype=np.int64)
                for name, K, c2w in self.camera_poses(frame)}

    def shadows(self, frame: int) -> list[np.ndarray]:
        """Contact-shadow footprints of vehicles and pedestrians at ``frame``."""
        out = []
        for a in self.agents:
            if a.category in ("vehicle", "pedestrian"):
                fp = a.footprint(frame)
                c = fp.mean(axis=0)
                out.append(c + (fp - c) * np.array([1.04, 1.04]) + 0.1)
        return out

    def render(
        self, frame: int
    ) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """Render all cameras of ``frame``: ``(name, K, cam_to_world, image, depth, instance, ground)``."""
        cfg = self.config
        draw = self.draw_list(frame)
        shadows = self.shadows(frame)
        out = []
        for name, K, c2w in self.camera_poses(frame):
            img, depth, inst, ground = render_view(
                self.layout,
                draw,
                K,
                c2w,
                cfg.width,
                cfg.height,
                self.texture_seed,
                cfg.texture_noise,
                cfg.max_ground_distance,
                shadows,
            )
            out.append((name, K, c2w, img, depth, inst, ground))
        return out


def generate_world(seed: int, config: WorldConfig | None = None) -> World:
    """Sample layout, ego route, agents, scenery and lighting for ``seed`` (no rendering)."""
    cfg = config or WorldConfig()
    rng = np.random.Generator(np.random.PCG64(seed))
    layout0 = sample_layout(rng)
    plan = sample_ego_plan(layout0, rng)
    # the world frame is the first ego pose: place the junction so the ego starts at the origin
    start_dist = layout0.stopline_s("W") + plan.speed * plan.t_junction
    layout = dataclasses.replace(layout0, center=(start_dist, (plan.lane + 0.5) * layout0.lane_w_h))
    times = np.arange(cfg.num_frames, dtype=np.float64) / cfg.fps
    ego_motion = bh.drive(layout, "W", plan.lane, plan.turn, plan.speed, plan.t_junction)
    ego = ego_motion.sample(times)
    poses = np.stack([pose_from_yaw(x, y, 0.0, h) for (x, y), h in zip(ego["xy"], ego["heading"])])
    poses[0] = np.eye(4)
    agents = populate(layout, times, ego, plan, rng, cfg.num_vehicles, cfg.num_pedestrians, cfg.num_static)
    scenery = build_scenery(layout, rng)
    az = rng.uniform(-np.pi, np.pi)
    el = rng.uniform(np.deg2rad(35.0), np.deg2rad(60.0))
    sun = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    texture_seed = int(rng.integers(0, 2**31 - 1))
    return World(seed, cfg, layout, plan, times, poses, ego["speed"], agents, scenery, Lighting(sun), texture_seed)


def _box_visible(world: World, agent: Agent, frame: int) -> bool:
    """Visibility without pixels: some camera sees the box's projection, within 80 m."""
    cfg = world.config
    h = float(agent.traj["heading"][frame])
    center = np.array([*agent.traj["xy"][frame], agent.size[2] / 2.0])
    corners = box_corners(center, np.asarray(agent.size), h)
    for _, K, c2w in world.camera_poses(frame):
        if np.linalg.norm(center - c2w[:3, 3]) > 80.0:
            continue
        if project_box_bounds(corners, K, c2w, cfg.width, cfg.height) is not None:
            return True
    return False


def generate_log(seed: int, config: WorldConfig | None = None, seq_id: str | None = None) -> SceneLog:
    """Generate, render and annotate one synthetic driving sequence.

    Args:
        seed: any non-negative integer; the only source of randomness.
        config: sequence parameters (``WorldConfig()`` when omitted).
        seq_id: sequence id, ``f"synth-{seed:06d}"`` when omitted.

    Returns:
        A validated ``SceneLog`` (``source="synthetic"``) with one ``CameraImage`` per frame and
        camera (frame-major, rig order), one track and object per agent, and the road map.
    """
    cfg = config or WorldConfig()
    seq_id = seq_id or default_seq_id(seed)
    t0 = time.perf_counter()
    world = generate_world(seed, cfg)
    n_frames, n_agents = cfg.num_frames, len(world.agents)
    timestamps = np.round(np.arange(n_frames) * (1e6 / cfg.fps)).astype(np.int64)
    visible = np.zeros((n_agents, n_frames), dtype=bool)
    images: list[CameraImage] = []
    for f in range(n_frames):
        split = split_for_frame(f, cfg.test_every)
        if cfg.render_images:
            for name, K, c2w, img, depth, inst, _ in world.render(f):
                counts = np.bincount(inst.ravel(), minlength=n_agents + 1)
                visible[:, f] |= counts[1:] >= cfg.min_visible_pixels
                images.append(
                    CameraImage(f, int(timestamps[f]), name, K, c2w, cfg.width, cfg.height, img, depth, inst, split)
                )
        else:
            for name, K, c2w in world.camera_poses(f):
                images.append(CameraImage(f, int(timestamps[f]), name, K, c2w, cfg.width, cfg.height, split=split))
            for k, agent in enumerate(world.agents):
                visible[k, f] = _box_visible(world, agent, f)
    tracks, objects = [], []
    frames = np.arange(n_frames, dtype=np.int64)
    for k, agent in enumerate(world.agents):
        size = np.tile(np.asarray(agent.size, dtype=np.float64), (n_frames, 1))
        center = np.concatenate([agent.traj["xy"], np.full((n_frames, 1), agent.size[2] / 2.0)], axis=1)
        track = Track(
            agent.object_id,
            frames.copy(),
            center,
            size,
            agent.traj["heading"].astype(np.float64),
            agent.traj["speed"].astype(np.float64),
            visible[k].copy(),
        )
        attrs = {"subtype": agent.subtype, **agent.appearance, "behavior": agent.behavior}
        desc = describe_track(track, agent.category, world.layout, world.ego_poses)
        appearance = describe_appearance(agent.category, attrs)
        attrs.update(
            caption_appearance=appearance,
            caption_motion=desc.motion,
            caption_location=desc.location,
            caption_frame=str(desc.ref_frame),
        )
        if agent.lookalike_group:
            attrs["lookalike_group"] = agent.lookalike_group
        caption = compose_caption(agent.category, appearance, desc.motion, desc.location)
        tracks.append(track)
        objects.append(
            ObjectInfo(agent.object_id, agent.category, node_type_for_category(agent.category), k + 1, caption, attrs)
        )
    metadata = {
        "seed": str(seed),
        "generator": WORLD_VERSION,
        "road_layout": world.layout.to_json(),
        "ego_route": f"W lane {world.plan.lane} {world.plan.turn}",
        "ego_speed_mps": f"{world.plan.speed:.2f}",
        **cfg.summary(),
    }
    log = SceneLog(
        seq_id=seq_id,
        source=SYNTHETIC_SOURCE,
        timestamps_us=timestamps,
        ego_poses=world.ego_poses,
        images=tuple(images),
        tracks=tuple(tracks),
        objects=tuple(objects),
        map_features=tuple(world.layout.map_features()),
        metadata=metadata,
    ).validate()
    logger.info(
        "generated %s: %d frames x %d cameras, %d objects in %.2fs",
        seq_id,
        n_frames,
        len(cfg.cameras),
        n_agents,
        time.perf_counter() - t0,
    )
    return log


def layout_from_log(log: SceneLog) -> RoadLayout:
    """The ``RoadLayout`` stored in a synthetic log's metadata."""
    return RoadLayout.from_json(log.metadata["road_layout"])


__all__ = ["World", "generate_world", "generate_log", "layout_from_log"]
