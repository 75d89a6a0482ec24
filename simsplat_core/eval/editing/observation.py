"""What the success checks look at: the editor's answer reduced to values, and rendered views.

The checks never ask the editor what it did. They read

* :class:`EditObservation` -- the agents before and after the edit (``scenario.agents.AgentStates``, the
  same data as the ``trajectories`` table), the appearance of inserted objects (:class:`AssetLook`, from
  the asset bank's metadata), or the refusal;
* :class:`ViewSet` s -- images and per-pixel ids of some frames and cameras: the edited Gaussian scene's
  renders (node ids), the world's own rendering of the same edit (``world_edit.py``, instance ids) and
  the log's images of the unedited scene (instance ids).

Which objects an edit removed, changed or added is measured by comparing the two ``AgentStates`` (ids
and trajectories), not taken from the editor's report.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.metrics import overlap_rows

#: Trajectories differing by more than this (metres / radians) at some valid step count as changed.
CHANGE_TOL = 1e-3


@dataclass(frozen=True)
class AssetLook:
    """What an inserted (or replacing) object looks like, from the asset bank's metadata.

    Attributes:
        category: ``"vehicle"``, ``"pedestrian"`` or ``"static"``.
        subtype: e.g. ``"SUV"``, ``"adult"``, ``"traffic cone"``.
        color: main colour (a pedestrian's upper-body colour); lower: a pedestrian's lower-body colour.
        size: box ``(length, width, height)`` metres.
        source_seq, source_object: where it was cut out (``""`` for procedural assets).
        asset_id: the bank's id.
    """

    category: str
    subtype: str
    color: str
    size: tuple[float, float, float]
    lower: str | None = None
    source_seq: str = ""
    source_object: str = ""
    asset_id: str = ""

    @classmethod
    def of_asset(cls, asset: Any) -> AssetLook:
        """From an ``editing.assets.bank.Asset`` (its ``attributes["lower_color"]`` names trousers)."""
        attributes = dict(getattr(asset, "attributes", {}) or {})
        return cls(asset.category, asset.subtype, asset.color, tuple(float(v) for v in asset.size),  # type: ignore[arg-type]
                   attributes.get("lower_color"), asset.source_seq, asset.source_object, asset.asset_id)


@dataclass(frozen=True, eq=False)
class EditObservation:
    """One method's answer to one prompt.

    Attributes:
        refused: the ``EditRefused.reason`` when the edit was refused, else ``None``.
        message: the refusal message (or the editor's summary).
        before, after: all agents before and after the edit (``None`` when refused).
        looks: ``object id -> AssetLook`` of every object the edit added (inserted or replacing).
        seconds: wall time of the edit (parse + ground + apply + validate).
        validation_ok: the editor's own validation verdict (reported, not used by the checks).
    """

    refused: str | None
    message: str = ""
    before: AgentStates | None = None
    after: AgentStates | None = None
    looks: dict[str, AssetLook] = field(default_factory=dict)
    seconds: float = 0.0
    validation_ok: bool | None = None

    @classmethod
    def refusal(cls, reason: str, message: str, seconds: float = 0.0) -> EditObservation:
        return cls(reason, message, seconds=seconds)

    @property
    def carried_out(self) -> bool:
        return self.refused is None and self.before is not None and self.after is not None


@dataclass(frozen=True)
class StateChanges:
    """Agents an edit removed, added and changed (measured from the two ``AgentStates``).

    Attributes:
        removed: ids present before, absent after.
        added: ids present after only.
        moved: ids present in both whose trajectory (valid steps, positions, headings) changed.
        redrawn: ids present in both drawn by another scene-graph node after the edit (replaced looks).
    """

    removed: tuple[str, ...]
    added: tuple[str, ...]
    moved: tuple[str, ...]
    redrawn: tuple[str, ...]


def trajectory_changed(before: AgentStates, after: AgentStates, object_id: str, tol: float = CHANGE_TOL) -> bool:
    """Whether ``object_id`` (in both) exists at other steps or is elsewhere / otherwise oriented."""
    i, j = before.index(object_id), after.index(object_id)
    if not np.array_equal(before.valid[i], after.valid[j]):
        return True
    steps = before.valid[i]
    if not steps.any():
        return False
    dxy = np.abs(before.xy[i, steps] - after.xy[j, steps]).max()
    dh = np.abs(np.angle(np.exp(1j * (before.heading[i, steps] - after.heading[j, steps])))).max()
    return bool(dxy > tol or dh > tol)


def state_changes(before: AgentStates, after: AgentStates) -> StateChanges:
    """What changed between two ``AgentStates`` of the same steps.

    Raises:
        ValueError: the states cover different steps.
    """
    if not np.array_equal(before.frame_idx, after.frame_idx):
        raise ValueError("state_changes: the states cover different frames")
    old, new = set(before.object_ids), set(after.object_ids)
    common = [o for o in before.object_ids if o in new]
    moved = tuple(o for o in common if trajectory_changed(before, after, o))
    redrawn = tuple(o for o in common if o != EGO_ID
                    and int(before.node_ids[before.index(o)]) != int(after.node_ids[after.index(o)]))
    return StateChanges(tuple(o for o in before.object_ids if o not in new),
                        tuple(o for o in after.object_ids if o not in old), moved, redrawn)


@dataclass(frozen=True, eq=False)
class ViewSet:
    """Images of ``F`` frames x ``C`` cameras with per-pixel ids.

    Attributes:
        frames: ``F`` log frame indices.
        cameras: ``C`` camera names.
        rgb: ``[F, C, H, W, 3]`` float32 in ``[0, 1]``.
        ids: ``[F, C, H, W]`` int32 node ids (Gaussian renders, ``-1`` = nothing opaque) or instance ids
            (world renders, ``0`` = background).
    """

    frames: tuple[int, ...]
    cameras: tuple[str, ...]
    rgb: np.ndarray
    ids: np.ndarray

    def __post_init__(self) -> None:
        f, c = len(self.frames), len(self.cameras)
        if self.rgb.shape[:2] != (f, c) or self.rgb.shape[-1] != 3 or self.ids.shape != self.rgb.shape[:4]:
            raise ValueError(f"ViewSet: rgb {self.rgb.shape} / ids {self.ids.shape} do not fit {f} frames x "
                             f"{c} cameras")

    def row(self, frame: int) -> int:
        return self.frames.index(frame)

    def take(self, frames: tuple[int, ...]) -> ViewSet:
        """The views of ``frames`` (each must be present)."""
        rows = [self.row(f) for f in frames]
        return ViewSet(tuple(frames), self.cameras, self.rgb[rows], self.ids[rows])


@dataclass(frozen=True, eq=False)
class PixelEvidence:
    """Views of the same frames and cameras for the pixel checks.

    Attributes:
        edited: the edited Gaussian scene (node ids).
        world_edited: the world's rendering of the same edit (instance ids, ``world_instance``).
        world_original: the log's images of the unedited scene (instance ids, ``original_instance``).
        world_instance, original_instance: ``object id -> instance id`` in those renders.
        native: object ids the world rendered as a world-native equivalent of what the editor drew
            (an object without one, e.g. a procedural asset the world cannot build, is drawn by a stand-in).
        reference_captions: per inserted / replacing object, the captioner's caption of the world's own
            rendering of an object with the *asked* colours at the same place (``pixels.check_appearance``).
        world_silhouette: per inserted / moved / redrawn object, ``[F, C]`` pixels it would cover in
            ``world_edited``'s views with nothing in front of it (``World.silhouette_pixels``); with its pixels in
            ``world_edited`` this tells how much of it the world shows (``pixels.expected_views``).
        ego_contact: log frames at which the ego, replaying its log, touches another agent of the edited scene
            (:func:`ego_contact_frames`): its cameras sit at or inside that agent, no view of them is judged.
    """

    edited: ViewSet
    world_edited: ViewSet
    world_original: ViewSet
    world_instance: dict[str, int]
    original_instance: dict[str, int]
    native: frozenset[str] = frozenset()
    reference_captions: dict[str, AppearanceCaption] = field(default_factory=dict)
    world_silhouette: dict[str, np.ndarray] = field(default_factory=dict)
    ego_contact: frozenset[int] = frozenset()


def ego_contact_frames(states: AgentStates) -> frozenset[int]:
    """Log frames at which the ego's box overlaps another agent's box in ``states`` (an edit made traffic stop in the
    path the ego replays; a reacting ego would have braked, the logged cameras drive on into it)."""
    if EGO_ID not in states.object_ids:
        return frozenset()
    touching = overlap_rows(states, [states.index(EGO_ID)])[0].any(axis=0)  # [T]
    return frozenset(int(f) for f in states.frame_idx[touching])


__all__ = ["CHANGE_TOL", "AssetLook", "EditObservation", "PixelEvidence", "StateChanges", "ViewSet",
           "ego_contact_frames", "state_changes", "trajectory_changed"]
