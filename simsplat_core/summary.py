"""A compact, serialisable summary of a ``SceneLog`` (what ``simsplat inspect`` prints)."""

from __future__ import annotations

from collections import Counter
from dataclasses import asdict, dataclass, field

import numpy as np

from simsplat_core.types import SceneLog


@dataclass(frozen=True)
class LogSummary:
    """Counts that describe one sequence.

    Attributes:
        seq_id, source: as in ``SceneLog``.
        num_frames: number of frames (time steps).
        duration_s: time between the first and last frame.
        cameras: camera name -> ``"WxH"``.
        num_images: camera images carrying pixels.
        objects_by_category: category -> number of objects.
        map_by_kind: map feature kind -> count.
        test_frames: frames held out for evaluation.
    """

    seq_id: str
    source: str
    num_frames: int
    duration_s: float
    cameras: dict[str, str]
    num_images: int
    objects_by_category: dict[str, int]
    map_by_kind: dict[str, int]
    test_frames: list[int] = field(default_factory=list)

    def to_dict(self) -> dict:
        return asdict(self)


def summarize_log(log: SceneLog) -> LogSummary:
    """Summarise ``log`` without touching pixels beyond checking their presence."""
    cameras: dict[str, str] = {}
    for img in log.images:
        cameras.setdefault(img.camera, f"{img.width}x{img.height}")
    ts = log.timestamps_us
    duration = float(ts[-1] - ts[0]) / 1e6 if len(ts) > 1 else 0.0
    test_frames = sorted({img.frame_idx for img in log.images if img.split == "test"})
    return LogSummary(
        seq_id=log.seq_id,
        source=log.source,
        num_frames=log.num_frames,
        duration_s=round(duration, 3),
        cameras=cameras,
        num_images=sum(img.image is not None for img in log.images),
        objects_by_category=dict(sorted(Counter(obj.category for obj in log.objects).items())),
        map_by_kind=dict(sorted(Counter(f.kind for f in log.map_features).items())),
        test_frames=[int(f) for f in np.asarray(test_frames, dtype=np.int64)],
    )
