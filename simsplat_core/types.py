"""The in-memory driving-log model shared by every loader and stage.

Conventions (fixed by ``DESIGN.md``):

* Coordinates are metres, right-handed. The *world frame* of a ``SceneLog`` is the first ego pose
  (ego frame: x forward, y left, z up), so ``ego_poses[0]`` is the identity.
* Cameras use the OpenCV convention (x right, y down, z forward); ``cam_to_world`` maps camera
  coordinates to world coordinates, ``K`` is the 3x3 pinhole intrinsic matrix.
* Time is integer microseconds (``timestamp_us``) plus a zero-based ``frame_idx``.
* Images are float32 ``[H, W, 3]`` in ``[0, 1]`` (display-referred, not linearised).

Everything here is frozen; arrays are treated as read-only by convention.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

#: Dataclass field metadata: a content key leaves the field out while it is ``None`` (so adding an optional
#: field keeps the keys of records that do not use it).
KEY_OMIT_WHEN_NONE = "key_omit_when_none"

logger = logging.getLogger(__name__)

#: Object categories understood by every stage. Loaders map their own taxonomies onto these.
CATEGORIES: tuple[str, ...] = ("vehicle", "pedestrian", "cyclist", "static", "sign", "other")
#: How an object is represented in the scene graph.
NODE_TYPES: tuple[str, ...] = ("rigid", "nonrigid", "static")
#: Kinds of map feature.
MAP_KINDS: tuple[str, ...] = (
    "lane",
    "road_edge",
    "crosswalk",
    "drivable_area",
    "sidewalk",
    "lane_marking",
)
SPLITS: tuple[str, ...] = ("train", "test")
#: ``SceneLog.source`` of the procedural world's logs (the only ones with ground-truth captions and masks).
SYNTHETIC_SOURCE = "synthetic"


class LogValidationError(ValueError):
    """A driving log violates the data model; the message names the field and the value."""


def node_type_for_category(category: str) -> str:
    """Default scene-graph node type for an object category.

    Vehicles and cyclists move rigidly, pedestrians deform, static objects never move.
    """
    if category == "pedestrian":
        return "nonrigid"
    if category in ("static", "sign"):
        return "static"
    return "rigid"


def split_for_frame(frame_idx: int, test_every: int = 10) -> str:
    """Paper protocol: every ``test_every``-th frame (1-based 10th, 20th, ...) is held out for test."""
    if test_every <= 0:
        return "train"
    return "test" if (frame_idx + 1) % test_every == 0 else "train"


def _require_shape(name: str, array: np.ndarray, shape: tuple[int | None, ...]) -> None:
    if array.ndim != len(shape) or any(s is not None and a != s for a, s in zip(array.shape, shape)):
        raise LogValidationError(f"{name}: expected shape {shape}, got {array.shape}")


@dataclass(frozen=True)
class CameraImage:
    """One camera image of one frame, plus optional per-pixel ground truth.

    Attributes:
        frame_idx: zero-based frame index.
        timestamp_us: capture time in microseconds.
        camera: camera name (e.g. ``"front"``, ``"FRONT_LEFT"``, ``"ring_front_center"``).
        K: ``[3, 3]`` float64 pinhole intrinsics.
        cam_to_world: ``[4, 4]`` float64 OpenCV camera-to-world transform.
        width, height: image size in pixels.
        image: ``[H, W, 3]`` float32 RGB in ``[0, 1]``, or ``None`` when the log has no pixels
            (e.g. annotation-only logs).
        depth: ``[H, W]`` float32 metric z-depth, or ``None``. ``+inf`` = the ray hits nothing (sky);
            ``nan`` = no measurement there (e.g. pixels between projected lidar points): never sky.
        instance: ``[H, W]`` int32 instance ids (``ObjectInfo.instance_id``; 0 = background), or ``None``.
        split: ``"train"`` or ``"test"``.
        valid_mask: ``[H, W]`` bool, ``True`` where the pixels show the scene (``False`` e.g. on the ego
            car's own body), or ``None`` when every pixel is valid. Losses, metrics and initialisation skip
            invalid pixels.
    """

    frame_idx: int
    timestamp_us: int
    camera: str
    K: np.ndarray
    cam_to_world: np.ndarray
    width: int
    height: int
    image: np.ndarray | None = None
    depth: np.ndarray | None = None
    instance: np.ndarray | None = None
    split: str = "train"
    valid_mask: np.ndarray | None = field(default=None, metadata={KEY_OMIT_WHEN_NONE: True})

    def validate(self) -> None:
        where = f"frame {self.frame_idx} camera {self.camera!r}"
        _require_shape(f"{where}: K", np.asarray(self.K), (3, 3))
        _require_shape(f"{where}: cam_to_world", np.asarray(self.cam_to_world), (4, 4))
        if self.split not in SPLITS:
            raise LogValidationError(f"{where}: split must be one of {SPLITS}, got {self.split!r}")
        hw = (self.height, self.width)
        if self.image is not None:
            _require_shape(f"{where}: image", self.image, (*hw, 3))
        if self.depth is not None:
            _require_shape(f"{where}: depth", self.depth, hw)
        if self.instance is not None:
            _require_shape(f"{where}: instance", self.instance, hw)
        if self.valid_mask is not None:
            _require_shape(f"{where}: valid_mask", self.valid_mask, hw)
            if self.valid_mask.dtype != np.bool_:
                raise LogValidationError(f"{where}: valid_mask must be bool, got {self.valid_mask.dtype}")


@dataclass(frozen=True)
class Track:
    """The 3D box track of one object, stored column-wise over the frames where it exists.

    Attributes:
        object_id: identifier unique within the log.
        frame_idx: ``[T]`` int64 frame indices, strictly increasing.
        center: ``[T, 3]`` float64 box centre in the world frame.
        size: ``[T, 3]`` float64 box length (along heading), width, height.
        heading: ``[T]`` float64 yaw around world z, radians, 0 = world +x.
        speed: ``[T]`` float64 metres per second (ground speed).
        visible: ``[T]`` bool, whether any camera sees the object in that frame.
    """

    object_id: str
    frame_idx: np.ndarray
    center: np.ndarray
    size: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    visible: np.ndarray

    def __len__(self) -> int:
        return int(self.frame_idx.shape[0])

    def validate(self) -> None:
        n = len(self)
        where = f"track {self.object_id!r}"
        _require_shape(f"{where}: center", self.center, (n, 3))
        _require_shape(f"{where}: size", self.size, (n, 3))
        for name in ("heading", "speed", "visible"):
            _require_shape(f"{where}: {name}", getattr(self, name), (n,))
        if n > 1 and np.any(np.diff(self.frame_idx) <= 0):
            raise LogValidationError(f"{where}: frame_idx must be strictly increasing")
        if not np.all(np.isfinite(self.center)):
            raise LogValidationError(f"{where}: center has non-finite values")

    def index_of(self, frame_idx: int) -> int | None:
        """Row of ``frame_idx`` in this track, or ``None`` when the object is absent then."""
        pos = int(np.searchsorted(self.frame_idx, frame_idx))
        if pos < len(self) and int(self.frame_idx[pos]) == frame_idx:
            return pos
        return None


@dataclass(frozen=True)
class ObjectInfo:
    """Static facts about one object.

    Attributes:
        object_id: matches ``Track.object_id``.
        category: one of ``CATEGORIES``.
        node_type: one of ``NODE_TYPES``.
        instance_id: positive integer used in instance masks and EXR ``id`` channels.
        caption: one-sentence description (appearance + motion + location), may be empty.
        attributes: free-form string facts, e.g. ``subtype``, ``color``, ``behavior``,
            ``caption_appearance``, ``caption_motion``, ``caption_location``.
    """

    object_id: str
    category: str
    node_type: str
    instance_id: int
    caption: str = ""
    attributes: dict[str, str] = field(default_factory=dict)

    def validate(self) -> None:
        where = f"object {self.object_id!r}"
        if self.category not in CATEGORIES:
            raise LogValidationError(f"{where}: category must be one of {CATEGORIES}, got {self.category!r}")
        if self.node_type not in NODE_TYPES:
            raise LogValidationError(f"{where}: node_type must be one of {NODE_TYPES}, got {self.node_type!r}")
        if self.instance_id <= 0:
            raise LogValidationError(f"{where}: instance_id must be positive, got {self.instance_id}")


@dataclass(frozen=True)
class MapFeature:
    """One map polyline or polygon.

    Attributes:
        feature_id: identifier unique within the log.
        kind: one of ``MAP_KINDS``. Polygons (``crosswalk``, ``drivable_area``, ``sidewalk``) are
            closed implicitly (last point connects to the first).
        points: ``[P, 3]`` float64 world coordinates.
    """

    feature_id: str
    kind: str
    points: np.ndarray

    def validate(self) -> None:
        where = f"map feature {self.feature_id!r}"
        if self.kind not in MAP_KINDS:
            raise LogValidationError(f"{where}: kind must be one of {MAP_KINDS}, got {self.kind!r}")
        _require_shape(f"{where}: points", self.points, (None, 3))


@dataclass(frozen=True)
class SceneLog:
    """One driving sequence in the shared model, whatever its source.

    Attributes:
        seq_id: sequence identifier, safe as a directory name.
        source: ``"synthetic"``, ``"waymo"``, ``"av2"``, ...
        timestamps_us: ``[F]`` int64 time of each frame.
        ego_poses: ``[F, 4, 4]`` float64 ego-to-world; ``ego_poses[0]`` is the identity.
        images: camera images, any order; may be empty for annotation-only logs.
        tracks: one ``Track`` per object.
        objects: one ``ObjectInfo`` per object (same ids as ``tracks``).
        map_features: road map.
        metadata: free-form string facts (seed, generator version, original file, city, ...).
    """

    seq_id: str
    source: str
    timestamps_us: np.ndarray
    ego_poses: np.ndarray
    images: tuple[CameraImage, ...] = ()
    tracks: tuple[Track, ...] = ()
    objects: tuple[ObjectInfo, ...] = ()
    map_features: tuple[MapFeature, ...] = ()
    metadata: dict[str, str] = field(default_factory=dict)

    @property
    def num_frames(self) -> int:
        return int(self.timestamps_us.shape[0])

    @property
    def cameras(self) -> tuple[str, ...]:
        """Camera names in first-seen order."""
        return tuple(dict.fromkeys(img.camera for img in self.images))

    def object(self, object_id: str) -> ObjectInfo:
        for obj in self.objects:
            if obj.object_id == object_id:
                return obj
        raise KeyError(f"{self.seq_id}: no object {object_id!r}")

    def track(self, object_id: str) -> Track:
        for tr in self.tracks:
            if tr.object_id == object_id:
                return tr
        raise KeyError(f"{self.seq_id}: no track {object_id!r}")

    def images_at(self, frame_idx: int) -> tuple[CameraImage, ...]:
        return tuple(img for img in self.images if img.frame_idx == frame_idx)

    def validate(self) -> SceneLog:
        """Check every invariant; raise ``LogValidationError`` naming the offending field. Returns self."""
        f = self.num_frames
        _require_shape(f"{self.seq_id}: ego_poses", self.ego_poses, (f, 4, 4))
        if f > 1 and np.any(np.diff(self.timestamps_us) <= 0):
            raise LogValidationError(f"{self.seq_id}: timestamps_us must be strictly increasing")
        for img in self.images:
            img.validate()
            if not 0 <= img.frame_idx < f:
                raise LogValidationError(f"{self.seq_id}: image frame_idx {img.frame_idx} outside [0, {f})")
        for tr in self.tracks:
            tr.validate()
            if len(tr) and (tr.frame_idx[0] < 0 or tr.frame_idx[-1] >= f):
                raise LogValidationError(f"{self.seq_id}: track {tr.object_id!r} has frames outside [0, {f})")
        track_ids = {tr.object_id for tr in self.tracks}
        object_ids = [obj.object_id for obj in self.objects]
        if len(set(object_ids)) != len(object_ids):
            raise LogValidationError(f"{self.seq_id}: duplicate object_id in objects")
        if set(object_ids) != track_ids:
            missing = sorted(track_ids ^ set(object_ids))[:5]
            raise LogValidationError(f"{self.seq_id}: objects and tracks disagree on ids, e.g. {missing}")
        instance_ids = [obj.instance_id for obj in self.objects]
        if len(set(instance_ids)) != len(instance_ids):
            raise LogValidationError(f"{self.seq_id}: duplicate instance_id in objects")
        for obj in self.objects:
            obj.validate()
        for feat in self.map_features:
            feat.validate()
        return self


#: A callable that produces a ``SceneLog``; used by flows to defer heavy loading to workers.
SceneLogFactory = Callable[[], SceneLog]
