"""Training samples for the trajectory encoder: auto-labelled trajectories, random windows and mirrored logs.

Every movable object contributes its whole trajectory plus ``windows_per_track`` random windows of
it (each at least ``min_window_s`` long), and each window is *re-labelled* by the rule-based
labeller, so a window that cuts a left turn short is labelled with what it still shows. With
``mirror`` the log is also reflected across the world x axis (``y -> -y``), which turns left-hand
manoeuvres into right-hand ones (and swaps left/right sectors) and balances the classes; labels
are recomputed on the mirrored log.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.language.alignment.motion_encoder import InputConfig, trajectory_inputs
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.motion_labels import LabelThresholds, MotionLabel, label_trajectory
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import AGENT_KINDS, ObjectTrajectory, log_trajectories
from simsplat_core.types import SYNTHETIC_SOURCE, SceneLog

logger = logging.getLogger(__name__)

_MIRROR = np.diag([1.0, -1.0, 1.0, 1.0])


def mirror_log(log: SceneLog) -> SceneLog:
    """The log reflected across the world x axis (tracks, headings, ego poses, map); images dropped."""
    tracks = tuple(
        dataclasses.replace(tr, center=tr.center * np.array([1.0, -1.0, 1.0]), heading=-tr.heading)
        for tr in log.tracks
    )
    feats = tuple(dataclasses.replace(f, points=f.points * np.array([1.0, -1.0, 1.0])) for f in log.map_features)
    return dataclasses.replace(
        log,
        seq_id=f"{log.seq_id}-mirrored",
        ego_poses=_MIRROR @ log.ego_poses @ _MIRROR,
        images=(),
        tracks=tracks,
        map_features=feats,
    )


@dataclass(frozen=True)
class RealismConfig:
    """How synthetic logs are made to look like real tracks for training (``realistic_log``).

    Synthetic trajectories are exact, short (4 s at 10 Hz) and fast; real annotated tracks (Argoverse 2:
    15.6 s at 10 Hz) jitter by centimetres, have gaps where the object was not annotated, and move slower
    on average in city traffic. Each synthetic log adds ``copies`` re-timed, jittered and thinned copies
    of itself (the clean log is kept), relabelled by the auto-labeller like any real log.

    Attributes:
        copies: realistic copies per synthetic log (0: off).
        time_stretch: each copy's timestamps are stretched by a factor drawn uniformly from this range:
            tracks last longer and move proportionally slower.
        position_noise_m: std of the per-frame jitter of box centres (x, y), metres.
        heading_noise_rad: std of the per-frame jitter of box headings, radians.
        drop_rate: share of a track's interior frames dropped (annotation gaps).
        lateral_offset_m: std of a per-track sideways offset of the box centres (along the normal of the
            box heading, frame by frame): real drivers are not centred on the map's lane centre lines
            (synthetic ones are, exactly), so without it a car off the centre line looks parked.
    """

    copies: int = 1
    time_stretch: tuple[float, float] = (1.0, 3.0)
    position_noise_m: float = 0.05
    heading_noise_rad: float = 0.02
    drop_rate: float = 0.1
    lateral_offset_m: float = 0.0


def realistic_log(log: SceneLog, config: RealismConfig, rng: np.random.Generator, copy: int = 0) -> SceneLog:
    """One realistic copy of ``log`` (``RealismConfig``): stretched time, jittered and thinned tracks,
    images dropped; map and ego poses kept (the ego's own speed scales with the time stretch)."""
    stretch = float(rng.uniform(*config.time_stretch))
    ts = np.asarray(log.timestamps_us, dtype=np.int64)
    timestamps = ts[0] + np.round((ts - ts[0]) * stretch).astype(np.int64)
    tracks = []
    for tr in log.tracks:
        n = len(tr)
        keep = np.ones(n, dtype=bool)
        if n > 4 and config.drop_rate > 0:
            keep[1:-1] = rng.random(n - 2) >= config.drop_rate
        center = np.array(tr.center, dtype=np.float64)
        heading = np.asarray(tr.heading, dtype=np.float64)
        offset = rng.normal(0.0, config.lateral_offset_m) if config.lateral_offset_m > 0 else 0.0
        center[:, :2] += offset * np.stack([-np.sin(heading), np.cos(heading)], axis=1)  # [n, 2] left normal
        center[:, :2] += rng.normal(0.0, config.position_noise_m, size=(n, 2))
        heading = heading + rng.normal(0.0, config.heading_noise_rad, size=n)
        tracks.append(dataclasses.replace(
            tr, frame_idx=tr.frame_idx[keep], center=center[keep], size=tr.size[keep], heading=heading[keep],
            speed=tr.speed[keep] / stretch, visible=tr.visible[keep]))
    return dataclasses.replace(log, seq_id=f"{log.seq_id}-real{copy}", timestamps_us=timestamps, images=(),
                               tracks=tuple(tracks))


@dataclass(frozen=True)
class SampleConfig:
    """Which samples a log yields.

    Attributes:
        windows_per_track: random windows per trajectory, in addition to the whole trajectory.
        min_window_s: shortest window.
        min_frames: trajectories with fewer frames are skipped.
        mirror: add the mirrored log.
        realism: realistic copies of synthetic logs (``RealismConfig``; ``None``: off). Real logs are
            used as they are.
    """

    windows_per_track: int = 6
    min_window_s: float = 1.0
    min_frames: int = 3
    mirror: bool = True
    realism: RealismConfig | None = None


@dataclass(frozen=True)
class TrainingSamples:
    """Stacked samples.

    Attributes:
        seq: ``[N, L, C]`` float32.
        glob: ``[N, G]`` float32.
        kind: ``[N]`` int64 index into ``AGENT_KINDS``.
        motion: ``[N]`` int64 index into the kind's motion codebook.
        sector, context: ``[N]`` int64 indices into the sector / context codebooks.
    """

    seq: np.ndarray
    glob: np.ndarray
    kind: np.ndarray
    motion: np.ndarray
    sector: np.ndarray
    context: np.ndarray

    def __len__(self) -> int:
        return int(self.kind.shape[0])


def _windows(traj: ObjectTrajectory, count: int, min_s: float, rng: np.random.Generator) -> list[ObjectTrajectory]:
    """The whole trajectory plus ``count`` random contiguous windows of at least ``min_s`` seconds."""
    out = [traj]
    if traj.duration <= min_s:
        return out
    for _ in range(count):
        length = rng.uniform(min_s, traj.duration)
        start = rng.uniform(traj.t[0], traj.t[-1] - length)
        i0 = int(np.searchsorted(traj.t, start))
        i1 = int(np.searchsorted(traj.t, start + length, side="right"))
        if i1 - i0 >= 2:
            out.append(traj.window(slice(i0, i1)))
    return out


def log_samples(
    log: SceneLog,
    input_config: InputConfig,
    sample_config: SampleConfig,
    thresholds: LabelThresholds,
    rng: np.random.Generator,
) -> list[tuple[np.ndarray, np.ndarray, MotionLabel]]:
    """``(seq, glob, label)`` for every window of every movable object of one log (not mirrored)."""
    map_context = MapContext.from_features(log.map_features) if log.map_features else None
    out = []
    for traj in log_trajectories(log, map_context, min_frames=sample_config.min_frames).values():
        for window in _windows(traj, sample_config.windows_per_track, sample_config.min_window_s, rng):
            label = label_trajectory(window, log.ego_poses, map_context, thresholds)
            seq, glob = trajectory_inputs(window, log.ego_poses, map_context, input_config)
            out.append((seq, glob, label))
    return out


def build_samples(
    logs: Sequence[SceneLog],
    codebooks: MotionCodebooks,
    input_config: InputConfig,
    sample_config: SampleConfig,
    thresholds: LabelThresholds,
    seed: int,
) -> TrainingSamples:
    """All samples of ``logs`` (and their mirrors), stacked; deterministic for a given ``seed``."""
    rng = np.random.default_rng(seed)
    rows: list[tuple[np.ndarray, np.ndarray, MotionLabel]] = []
    for log in logs:
        bases = [log]
        realism = sample_config.realism
        if realism is not None and log.source == SYNTHETIC_SOURCE:
            bases += [realistic_log(log, realism, rng, copy) for copy in range(realism.copies)]
        variants = [v for base in bases for v in ((base, mirror_log(base)) if sample_config.mirror else (base,))]
        for variant in variants:
            rows += log_samples(variant, input_config, sample_config, thresholds, rng)
    if not rows:
        raise ValueError("no trainable trajectories in the given logs")
    labels = [r[2] for r in rows]
    samples = TrainingSamples(
        seq=np.stack([r[0] for r in rows]),
        glob=np.stack([r[1] for r in rows]),
        kind=np.array([AGENT_KINDS.index(lb.kind) for lb in labels], dtype=np.int64),
        motion=np.array([codebooks.motion(lb.kind).index(lb.motion) for lb in labels], dtype=np.int64),
        sector=np.array([codebooks.sector.index(lb.sector) for lb in labels], dtype=np.int64),
        context=np.array([codebooks.context.index(lb.context) for lb in labels], dtype=np.int64),
    )
    logger.info("built %d training samples from %d logs", len(samples), len(logs))
    return samples

