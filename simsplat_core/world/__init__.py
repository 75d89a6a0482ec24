"""Procedural driving world: the project's embedded default data (a stand-in for Waymo logs).

``generate_log(seed, config)`` builds a four-way intersection with multi-lane roads, crosswalks and
sidewalks, drives the ego through it with a three-camera front rig, populates the scene with
vehicles, articulated pedestrians and street furniture (including deliberate look-alikes), renders
RGB, z-depth and instance masks with its own rasterizer, and annotates every object with a box track
and captions derived from its trajectory.

    from simsplat_core.world import WorldConfig, generate_log
    log = generate_log(seed=7, config=WorldConfig())
"""

from simsplat_core.world.captions import (
    TrackDescription,
    describe_appearance,
    describe_location,
    describe_motion,
    describe_track,
    reference_frame,
)
from simsplat_core.world.config import GENERATOR_VERSION, WORLD_VERSION, CameraSpec, WorldConfig, default_seq_id
from simsplat_core.world.generate import World, generate_log, generate_world, layout_from_log
from simsplat_core.world.road import RoadLayout

__all__ = [
    "GENERATOR_VERSION",
    "CameraSpec",
    "RoadLayout",
    "TrackDescription",
    "WORLD_VERSION",
    "World",
    "WorldConfig",
    "default_seq_id",
    "describe_appearance",
    "describe_location",
    "describe_motion",
    "describe_track",
    "generate_log",
    "generate_world",
    "layout_from_log",
    "reference_frame",
]
