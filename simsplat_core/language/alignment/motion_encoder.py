"""Trajectory encoder: fixed-length ego-relative trajectory tensors -> logits over the codebook prototypes.

Input of one object (or one window of its trajectory), built by ``trajectory_inputs``:

* ``seq`` ``[L, C]``: the trajectory resampled at ``L`` instants evenly spread over its time span
  (linear interpolation between observed frames). Channels (``SEQ_CHANNELS``): position, heading and
  velocity in the ego frame at the reference frame; position and heading relative to the object's
  own first pose; forward and sideways speed; signed lane offset; map facts (drivable, sidewalk,
  crosswalk, intersection, lane distance); and a mask that is 0 where the nearest observed frame is
  more than ``max_gap_s`` away (missing frames).
* ``glob`` ``[G]``: duration, agent kind, which map layers exist, and the ego-relative pose and map
  facts at the reference frame (what location refers to) (``GLOBAL_CHANNELS``).

Positions are divided by ``position_scale_m`` and clipped to ``[-4, 4]``, speeds by
``speed_scale_mps``.

The network (``TrajectoryEncoder``) is a masked MLP: masked steps are zeroed, the sequence is
flattened with the globals, two GELU layers of width ``hidden`` feed four linear heads (vehicle
motion, pedestrian motion, location sector, location context). A trajectory has 5-156 frames here,
so a fixed-length resampling plus an MLP is as expressive as a GRU and trains in seconds on a CPU.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import (
    ObjectTrajectory,
    ego_yaw,
    resample_series,
    rotate_to_ego,
    to_ego_frame,
)

SEQ_CHANNELS: tuple[str, ...] = (
    "ego_x", "ego_y", "ego_cos_h", "ego_sin_h", "ego_vx", "ego_vy",
    "obj_x", "obj_y", "obj_cos_h", "obj_sin_h", "v_forward", "v_sideways",
    "lane_offset", "lane_known", "on_drivable", "on_sidewalk", "in_crosswalk", "at_intersection", "lane_dist",
    "mask",
)  # fmt: skip
GLOBAL_CHANNELS: tuple[str, ...] = (
    "duration", "is_pedestrian", "has_drivable", "has_sidewalks", "has_lanes",
    "ref_x", "ref_y", "ref_cos_bearing", "ref_sin_bearing", "ref_cos_h", "ref_sin_h",
    "ref_on_drivable", "ref_on_sidewalk", "ref_in_crosswalk", "ref_at_intersection", "ref_lane_dist",
)  # fmt: skip
HEADS: tuple[str, ...] = ("vehicle", "pedestrian", "sector", "context")


@dataclass(frozen=True)
class InputConfig:
    """How trajectories become tensors.

    Attributes:
        steps: resampled length ``L``.
        position_scale_m, speed_scale_mps, duration_scale_s: normalisers.
        max_gap_s: resampled instants farther than this from an observed frame are masked.
        lane_dist_clip_m: lane distances are clipped to this before scaling to ``[0, 1]``.
    """

    steps: int = 16
    position_scale_m: float = 30.0
    speed_scale_mps: float = 10.0
    duration_scale_s: float = 10.0
    max_gap_s: float = 0.5
    lane_dist_clip_m: float = 5.0


def _map_channels(traj: ObjectTrajectory, clip_m: float) -> np.ndarray:
    """``[T, 7]`` lane offset, lane known, drivable, sidewalk, crosswalk, intersection, lane distance."""
    n = len(traj)
    if traj.facts is None:
        return np.zeros((n, 7))
    f = traj.facts
    known = np.isfinite(f.lane_offset)
    lane_dist = np.where(np.isfinite(f.lane_dist), np.minimum(f.lane_dist, clip_m), clip_m) / clip_m
    return np.stack(
        [
            np.where(known, np.clip(f.lane_offset, -3.0, 3.0) / 2.0, 0.0),
            known,
            f.on_drivable,
            f.on_sidewalk,
            f.in_crosswalk,
            f.at_intersection,
            lane_dist,
        ],
        axis=1,
    ).astype(np.float64)


def trajectory_inputs(
    traj: ObjectTrajectory,
    ego_poses: np.ndarray,
    map_context: MapContext | None,
    config: InputConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """``(seq [L, C], glob [G])`` float32 inputs of one trajectory (``ego_poses`` ``[F, 4, 4]``)."""
    ref = traj.reference_row()
    pose = ego_poses[int(traj.frame_idx[ref])]
    yaw = ego_yaw(pose)
    pos_s, v_s = config.position_scale_m, config.speed_scale_mps

    ego_xy = np.clip(to_ego_frame(traj.xy, pose) / pos_s, -4.0, 4.0)
    ego_h = traj.heading - yaw
    ego_v = rotate_to_ego(traj.velocity, pose) / v_s
    h0 = traj.heading[0]
    c0, s0 = np.cos(h0), np.sin(h0)
    rel = traj.xy - traj.xy[0]
    obj_xy = np.clip(np.stack([c0 * rel[:, 0] + s0 * rel[:, 1], -s0 * rel[:, 0] + c0 * rel[:, 1]], axis=1) / pos_s,
                     -4.0, 4.0)
    obj_h = traj.heading - h0
    ch, sh = np.cos(traj.heading), np.sin(traj.heading)
    v_fwd = (traj.velocity[:, 0] * ch + traj.velocity[:, 1] * sh) / v_s
    v_side = (-traj.velocity[:, 0] * sh + traj.velocity[:, 1] * ch) / v_s
    per_row = np.concatenate(
        [
            ego_xy,
            np.stack([np.cos(ego_h), np.sin(ego_h)], axis=1),
            ego_v,
            obj_xy,
            np.stack([np.cos(obj_h), np.sin(obj_h), v_fwd, v_side], axis=1),
            _map_channels(traj, config.lane_dist_clip_m),
        ],
        axis=1,
    )  # [T, C - 1]
    at = np.linspace(traj.t[0], traj.t[-1], config.steps)
    seq = resample_series(traj.t, per_row, at)
    gap = np.abs(at[:, None] - traj.t[None, :]).min(axis=1)
    mask = (gap <= config.max_gap_s).astype(np.float64)
    seq = np.concatenate([seq * mask[:, None], mask[:, None]], axis=1)

    ref_xy = to_ego_frame(traj.xy[ref : ref + 1], pose)[0]
    bearing = np.arctan2(ref_xy[1], ref_xy[0])
    ref_map = _map_channels(traj.window(slice(ref, ref + 1)), config.lane_dist_clip_m)[0, 2:]
    has = (
        (map_context.has_drivable, map_context.has_sidewalks, map_context.has_lanes)
        if map_context is not None
        else (False, False, False)
    )
    glob = np.array(
        [
            traj.duration / config.duration_scale_s,
            float(traj.kind == "pedestrian"),
            *map(float, has),
            *np.clip(ref_xy / pos_s, -4.0, 4.0),
            np.cos(bearing),
            np.sin(bearing),
            np.cos(ego_h[ref]),
            np.sin(ego_h[ref]),
            *ref_map,
        ]
    )
    return seq.astype(np.float32), glob.astype(np.float32)


class TrajectoryEncoder(nn.Module):
    """Masked MLP from ``seq [N, L, C]`` and ``glob [N, G]`` to logits of every codebook head.

    Args:
        steps: ``L``.
        head_sizes: prototypes per head, keys ``HEADS``.
        hidden: trunk width.
        dropout: dropout after each trunk layer (training only).
    """

    def __init__(self, steps: int, head_sizes: dict[str, int], hidden: int = 128, dropout: float = 0.1) -> None:
        super().__init__()
        in_dim = steps * len(SEQ_CHANNELS) + len(GLOBAL_CHANNELS)
        self.trunk = nn.Sequential(
            nn.Linear(in_dim, hidden),
            nn.GELU(),
            nn.Dropout(dropout),
            nn.Linear(hidden, hidden),
            nn.GELU(),
            nn.Dropout(dropout),
        )
        self.heads = nn.ModuleDict({name: nn.Linear(hidden, head_sizes[name]) for name in HEADS})

    def forward(self, seq: torch.Tensor, glob: torch.Tensor) -> dict[str, torch.Tensor]:
        """Logits ``{head: [N, K_head]}``."""
        x = torch.cat([seq.flatten(1), glob], dim=1)  # [N, L * C + G]
        h = self.trunk(x)
        return {name: head(h) for name, head in self.heads.items()}
