"""Helpers shared by the real-log loaders: taxonomy-free track assembly, ids, visibility."""

from __future__ import annotations

import json
import logging
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np

from simsplat_core.data.errors import CorruptLogError
from simsplat_core.data.protowire import MessageSchema, ProtoDecodeError, decode_message
from simsplat_core.data.tfrecord import iter_tfrecords
from simsplat_core.geometry import box_corners_batch, invert_transform, project_box_bounds, transform_points
from simsplat_core.types import CameraImage, LogValidationError, SceneLog, Track, split_for_frame

_Parsed = TypeVar("_Parsed")

#: ``SceneLog.metadata`` key of explicit lane connectivity: JSON ``{lane feature id: [successor ids]}``.
LANE_SUCCESSORS_KEY = "lane_successors"
#: ``SceneLog.metadata`` key of the map-feature attributes a Waymo Open Motion / ScenarioNet export needs: JSON
#: ``{feature id: {"type": WOMD type name, "entry_lanes": [ids], "left_neighbors": [ids], "right_neighbors": [ids],
#: "speed_limit_mph": float}}`` with only the keys the source gives (exit lanes are ``LANE_SUCCESSORS_KEY``).
MAP_FEATURE_ATTRIBUTES_KEY = "map_feature_attributes"

logger = logging.getLogger(__name__)


def lane_successors(log: SceneLog) -> dict[str, list[str]] | None:
    """The explicit lane successors a loader stored (``LANE_SUCCESSORS_KEY``), or ``None`` when absent.

    Pass the result as ``LaneGraph.from_features(..., successors=...)``.
    """
    raw = log.metadata.get(LANE_SUCCESSORS_KEY)
    if raw is None:
        return None
    value = json.loads(raw)
    if not isinstance(value, dict):
        raise ValueError(f"{log.seq_id}: metadata {LANE_SUCCESSORS_KEY!r} is not a JSON object")
    return {str(k): [str(v) for v in vs] for k, vs in value.items()}


def map_feature_attributes(log: SceneLog) -> dict[str, dict[str, object]] | None:
    """The map-feature attributes a loader stored (``MAP_FEATURE_ATTRIBUTES_KEY``), or ``None`` when absent.

    Raises:
        ValueError: the entry is not a JSON object of objects (names the sequence and the feature).
    """
    raw = log.metadata.get(MAP_FEATURE_ATTRIBUTES_KEY)
    if raw is None:
        return None
    value = json.loads(raw)
    if not isinstance(value, dict):
        raise ValueError(f"{log.seq_id}: metadata {MAP_FEATURE_ATTRIBUTES_KEY!r} is not a JSON object")
    for feature_id, attributes in value.items():
        if not isinstance(attributes, dict):
            raise ValueError(f"{log.seq_id}: metadata {MAP_FEATURE_ATTRIBUTES_KEY!r}[{feature_id!r}] is not an object")
    return {str(k): dict(v) for k, v in value.items()}


def parse_tfrecords(path: Path, parse: Callable[[bytes], _Parsed]) -> list[tuple[int, _Parsed]]:
    """``(record index, parse(record data))`` for every CRC-verified record of a TFRecord file, in file order.

    Raises:
        CorruptLogError: framing or checksum damage (see ``tfrecord.iter_tfrecords``), a
            ``ProtoDecodeError`` from ``parse`` (re-raised naming the record, its byte offset and the
            field path), or a file without records.
    """
    parsed = []
    for record in iter_tfrecords(path):
        try:
            parsed.append((record.index, parse(record.data)))
        except ProtoDecodeError as exc:
            raise CorruptLogError(
                path,
                f"record {record.index} (byte offset {record.offset}), field {exc.field_path!r}",
                exc.reason + (f" (at byte {exc.offset} of the record)" if exc.offset >= 0 else ""),
                record_index=record.index,
                offset=record.offset,
            ) from exc
    if not parsed:
        raise CorruptLogError(path, "file", "no records")
    return parsed


def first_record_has(path: Path, signature: MessageSchema, field: str) -> bool:
    """Whether the first record of the TFRecord file ``path`` decodes as ``signature`` with ``field`` set.

    A cheap content test for telling proto types apart (log-source detection): ``signature`` names a few
    top-level fields whose wire types differ between the candidate messages. Never raises: an unreadable,
    damaged or empty file is ``False``.
    """
    try:
        record = next(iter_tfrecords(path), None)
        if record is None:
            return False
        return bool(decode_message(record.data, signature).get(field))
    except (CorruptLogError, ProtoDecodeError, OSError):
        return False


def safe_seq_id(name: str) -> str:
    """``name`` with every character outside ``[A-Za-z0-9_.-]`` replaced by ``_`` (safe as a directory)."""
    cleaned = re.sub(r"[^A-Za-z0-9_.-]", "_", name).strip(".")
    return cleaned or "log"


@dataclass(frozen=True)
class BoxObservation:
    """One box of one object at one frame, already in the world frame.

    Attributes:
        frame_idx: frame index.
        center: ``[3]`` float64 world centre.
        size: ``[3]`` float64 length, width, height.
        heading: world yaw, radians.
        speed: ground speed in m/s, or ``nan`` to derive it by finite differences.
        visible: whether the object counts as seen in that frame.
    """

    frame_idx: int
    center: np.ndarray
    size: np.ndarray
    heading: float
    speed: float
    visible: bool


def finite_difference_speed(times_s: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """Horizontal speed ``[T]`` (m/s) of ``[T, 3]`` centres sampled at ``[T]`` strictly increasing times.

    Central differences inside, one-sided at the ends (``np.gradient`` with uneven spacing);
    a single sample has speed 0.
    """
    if times_s.shape[0] < 2:
        return np.zeros(times_s.shape[0])
    vx = np.gradient(centers[:, 0], times_s)
    vy = np.gradient(centers[:, 1], times_s)
    return np.hypot(vx, vy)


def build_track(object_id: str, observations: Sequence[BoxObservation], timestamps_us: np.ndarray) -> Track:
    """Assemble a ``Track`` from per-frame observations (any order; sorted by frame here).

    Speeds given as ``nan`` are filled from finite differences of the world centres over
    ``timestamps_us`` (``[F]`` int64, indexed by frame).
    """
    obs = sorted(observations, key=lambda o: o.frame_idx)
    frame_idx = np.array([o.frame_idx for o in obs], dtype=np.int64)
    center = np.array([o.center for o in obs], dtype=np.float64).reshape(-1, 3)
    speed = np.array([o.speed for o in obs], dtype=np.float64)
    missing = ~np.isfinite(speed)
    if missing.any():
        fd = finite_difference_speed(timestamps_us[frame_idx].astype(np.float64) * 1e-6, center)
        speed[missing] = fd[missing]
    return Track(
        object_id=object_id,
        frame_idx=frame_idx,
        center=center,
        size=np.array([o.size for o in obs], dtype=np.float64).reshape(-1, 3),
        heading=np.array([o.heading for o in obs], dtype=np.float64),
        speed=speed,
        visible=np.array([o.visible for o in obs], dtype=bool),
    )


def _frustum_planes(K: np.ndarray, width: int, height: int, near: float) -> np.ndarray:
    """``[5, 4]`` inward unit planes ``(n, d)`` of a pinhole camera's view frustum (``n . p + d >= 0`` inside)."""
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    x0, x1 = -cx / fx, (width - cx) / fx  # x/z range over the image
    y0, y1 = -cy / fy, (height - cy) / fy
    normals = np.array([[1.0, 0.0, -x0], [-1.0, 0.0, x1], [0.0, 1.0, -y0], [0.0, -1.0, y1]])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    planes = np.concatenate([normals, np.zeros((4, 1))], axis=1)
    return np.concatenate([planes, [[0.0, 0.0, 1.0, -near]]], axis=0)


def boxes_visible(
    centers: np.ndarray, sizes: np.ndarray, headings: np.ndarray, cameras: Sequence[CameraImage], near: float = 0.1
) -> np.ndarray:
    """Which boxes project inside at least one camera image (occlusion ignored).

    Args:
        centers: ``[M, 3]`` world box centres.
        sizes: ``[M, 3]`` length, width, height.
        headings: ``[M]`` world yaw.
        cameras: the cameras of one frame (``K``, ``cam_to_world``, ``width``, ``height`` used).

    Returns:
        ``[M]`` bool. A bounding-sphere frustum test discards clear misses; the rest get the exact
        ``geometry.project_box_bounds`` (near-plane clipped) test.
    """
    centers = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    sizes = np.asarray(sizes, dtype=np.float64).reshape(-1, 3)
    headings = np.asarray(headings, dtype=np.float64).reshape(-1)
    radius = 0.5 * np.linalg.norm(sizes, axis=1)  # [M]
    corners = box_corners_batch(centers, sizes, headings)  # [M, 8, 3]
    visible = np.zeros(centers.shape[0], dtype=bool)
    for cam in cameras:
        K = np.asarray(cam.K, dtype=np.float64)
        world_to_cam = invert_transform(np.asarray(cam.cam_to_world, dtype=np.float64))
        planes = _frustum_planes(K, cam.width, cam.height, near)
        signed = transform_points(world_to_cam, centers) @ planes[:, :3].T + planes[:, 3]  # [M, 5]
        todo = ~visible & np.all(signed >= -radius[:, None], axis=1)  # bounding sphere touches frustum
        if not todo.any():
            continue
        # Sufficient: some corner in front of the near plane projects inside the image.
        cam_corners = transform_points(world_to_cam, corners[todo].reshape(-1, 3)).reshape(-1, 8, 3)
        z = cam_corners[..., 2]
        uv = cam_corners[..., :2] / np.where(z > near, z, 1.0)[..., None] @ K[:2, :2].T + K[:2, 2]
        inside = (
            (z > near) & (uv[..., 0] >= 0) & (uv[..., 0] <= cam.width) & (uv[..., 1] >= 0) & (uv[..., 1] <= cam.height)
        )
        idx = np.flatnonzero(todo)
        visible[idx[inside.any(axis=1)]] = True
        # Exact, near-plane clipped test for boxes straddling the image border or the camera.
        for m in idx[~inside.any(axis=1)]:
            if project_box_bounds(corners[m], K, cam.cam_to_world, cam.width, cam.height, near) is not None:
                visible[m] = True
    return visible


def validated(log: SceneLog, path: str | Path) -> SceneLog:
    """``log.validate()``, re-raising a failure as ``CorruptLogError`` naming ``path``."""
    try:
        return log.validate()
    except LogValidationError as exc:
        raise CorruptLogError(path, "assembled scene log", str(exc)) from exc


def loaded(log: SceneLog, path: str | Path, started: float, name: str = "") -> SceneLog:
    """A loader's last step: ``validated(log, path)``, then one INFO line with what the log holds and the seconds
    since ``started`` (a ``time.perf_counter()`` value); ``name`` is the record's own id (a scenario's), if any."""
    validated(log, path)
    logger.info("loaded %s%s: %d frames, %d images, %d objects, %d map features in %.2f s", path,
                f" (scenario {name})" if name else "", log.num_frames, len(log.images), len(log.objects),
                len(log.map_features), time.perf_counter() - started)
    return log


#: Logs with this many frames (inclusive) hold out their middle frame instead of every 10th.
SHORT_LOG_FRAMES = (3, 9)


def held_out_split(frame_idx: int, num_frames: int) -> str:
    """``"test"`` or ``"train"`` for a frame of a real log of ``num_frames`` frames.

    Short logs (``SHORT_LOG_FRAMES``) would hold out nothing under ``types.split_for_frame``'s every-10th
    rule, so they hold out their middle frame ``num_frames // 2`` (all cameras); longer logs follow
    ``split_for_frame``.
    """
    low, high = SHORT_LOG_FRAMES
    if low <= num_frames <= high:
        return "test" if frame_idx == num_frames // 2 else "train"
    return split_for_frame(frame_idx)
