"""Configuration of the procedural driving world: sequence length, image size, camera rig, agent counts.

Everything here is a frozen dataclass so a config can be hashed into cache keys and compared; the
generator never mutates it. ``WorldConfig.summary()`` gives the flat string dict stored in
``SceneLog.metadata``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

#: Version of the generator's output; bump it whenever the same seed and config would give different logs
#: (it feeds the content keys of stored synthetic logs).
WORLD_VERSION = "simsplat-world/1.0"
GENERATOR_VERSION = WORLD_VERSION


def default_seq_id(seed: int) -> str:
    """Sequence id of the synthetic log of ``seed``: ``synth-000042``."""
    return f"synth-{seed:06d}"


@dataclass(frozen=True)
class CameraSpec:
    """One pinhole camera rigidly mounted on the ego vehicle.

    Attributes:
        name: camera name used in ``CameraImage.camera``.
        yaw_deg: mounting yaw in degrees about ego +z (positive = looking left).
        pitch_deg: downward tilt in degrees (positive = looking down).
        hfov_deg: horizontal field of view in degrees (square pixels, principal point at the centre).
        position: ``(x, y, z)`` mounting point in the ego frame, metres (ego origin is on the ground).
    """

    name: str
    yaw_deg: float
    pitch_deg: float = 3.0
    hfov_deg: float = 80.0
    position: tuple[float, float, float] = (1.5, 0.0, 1.6)


def default_cameras() -> tuple[CameraSpec, ...]:
    """The three-camera front rig: front, front-left (+55 deg) and front-right (-55 deg)."""
    return (
        CameraSpec("front", 0.0, 3.0, 80.0, (1.6, 0.0, 1.6)),
        CameraSpec("front_left", 55.0, 3.0, 80.0, (1.5, 0.25, 1.6)),
        CameraSpec("front_right", -55.0, 3.0, 80.0, (1.5, -0.25, 1.6)),
    )


@dataclass(frozen=True)
class WorldConfig:
    """Parameters of one generated sequence.

    Attributes:
        num_frames: number of frames ``F``.
        width, height: image size in pixels.
        fps: frame rate; timestamps are ``round(frame_idx * 1e6 / fps)`` microseconds.
        test_every: every ``test_every``-th frame is a test frame (``types.split_for_frame``).
        cameras: the camera rig.
        num_vehicles: inclusive ``(min, max)`` target count of vehicles (ego excluded).
        num_pedestrians: inclusive ``(min, max)`` target count of pedestrians.
        num_static: inclusive ``(min, max)`` target count of static objects (cones, barriers, signs).
        min_visible_pixels: an object is ``visible`` in a frame when its instance mask has at least
            this many pixels in some camera.
        texture_noise: amplitude of the deterministic procedural texture (0 disables it).
        render_images: when ``False`` no pixels are rendered (annotation-only log, fast);
            visibility then falls back to projected boxes.
        max_ground_distance: ground farther than this (metres along the ray) is drawn as sky.
    """

    num_frames: int = 40
    width: int = 240
    height: int = 160
    fps: float = 10.0
    test_every: int = 10
    cameras: tuple[CameraSpec, ...] = field(default_factory=default_cameras)
    num_vehicles: tuple[int, int] = (8, 14)
    num_pedestrians: tuple[int, int] = (4, 8)
    num_static: tuple[int, int] = (3, 6)
    min_visible_pixels: int = 8
    texture_noise: float = 0.06
    render_images: bool = True
    max_ground_distance: float = 400.0

    def __post_init__(self) -> None:
        if self.num_frames < 1:
            raise ValueError(f"num_frames must be >= 1, got {self.num_frames}")
        if self.width < 8 or self.height < 8:
            raise ValueError(f"image size must be at least 8x8, got {self.width}x{self.height}")
        if self.fps <= 0:
            raise ValueError(f"fps must be positive, got {self.fps}")
        if not self.cameras:
            raise ValueError("at least one camera is required")
        names = [c.name for c in self.cameras]
        if len(set(names)) != len(names):
            raise ValueError(f"camera names must be unique, got {names}")
        for label in ("num_vehicles", "num_pedestrians", "num_static"):
            lo, hi = getattr(self, label)
            if lo < 0 or hi < lo:
                raise ValueError(f"{label} must be a (min, max) pair with 0 <= min <= max, got {(lo, hi)}")

    @property
    def duration_s(self) -> float:
        """Time spanned by the sequence, ``(F - 1) / fps`` seconds."""
        return (self.num_frames - 1) / self.fps

    def summary(self) -> dict[str, str]:
        """Flat string facts for ``SceneLog.metadata``."""
        return {
            "num_frames": str(self.num_frames),
            "image_size": f"{self.width}x{self.height}",
            "fps": repr(float(self.fps)),
            "test_every": str(self.test_every),
            "cameras": ",".join(c.name for c in self.cameras),
            "config_json": json.dumps(asdict(self), sort_keys=True),
        }
