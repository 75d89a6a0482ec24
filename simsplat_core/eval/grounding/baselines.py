"""Baseline grounders for the grounding benchmark (SIMSplat Table 2) and an adapter for ``QueryEngine``.

All grounders share one call, ``ground(scene, text) -> tuple[int, ...]`` (node ids; empty = nothing
matches), the shape of ``QueryEngine.ground(scene, text).node_ids``.

* ``AppearanceOnlyGrounder`` -- LangSplat-like: the whole query is embedded (E5 *query* role) and
  compared by cosine with every node's appearance feature ``f_app``; the best node is returned. No
  parsing, no motion, no threshold: it always answers with exactly one node.
* ``FrameCaptionGrounder`` -- 4D-LangSplat-like: time-varying captions. For every node and every frame
  in which the object is visible, a caption = the node's appearance caption + the object's
  *instantaneous* state in that frame, read off its track the way a multimodal LLM describing that one
  frame would (``instantaneous_state``: "stopped", "moving", "turning left"/"right" for vehicles;
  "standing", "walking", "walking across the road" for pedestrians). Captions are embedded as E5
  passages; a node's score is the maximum cosine over its frames; the best node is returned. Needs the
  logs (tracks and map) besides the scenes.
* ``EngineGrounder`` -- wraps anything with ``ground(scene, text)`` returning an object with
  ``node_ids`` (the ``QueryEngine``).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import numpy as np

from simsplat_core.language.codebooks import cosine_scores
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import TextEncoder
from simsplat_core.scenario.trajectory import ObjectTrajectory, log_trajectories, moving_average
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: Thresholds of ``instantaneous_state``.
STOPPED_MPS = 0.5
TURN_RATE_DEG_S = 8.0


class AppearanceOnlyGrounder:
    """LangSplat-like baseline: argmax over nodes of ``cos(E5_query(text), f_app)``.

    Args:
        text_encoder: the encoder the scene's ``f_app`` features live in.
    """

    name = "LangSplat-like"

    def __init__(self, text_encoder: TextEncoder) -> None:
        self.text_encoder = text_encoder

    def scores(self, scene: LanguageScene, text: str) -> dict[int, float]:
        """``node_id -> cosine`` of every node with an appearance feature."""
        _check_space(scene, self.text_encoder)
        nodes = [n for n in scene.nodes if n.f_app is not None]
        if not nodes:
            return {}
        q = self.text_encoder.encode_queries([text])[0]
        sims = cosine_scores(np.stack([n.f_app for n in nodes if n.f_app is not None]), q)
        return {n.node_id: float(s) for n, s in zip(nodes, sims)}

    def ground(self, scene: LanguageScene, text: str) -> tuple[int, ...]:
        return _best_node(self.scores(scene, text))


def _best_node(scores: Mapping[int, float]) -> tuple[int, ...]:
    """The node of the highest score, as a one-node answer (no answer without scores)."""
    return (max(scores, key=scores.__getitem__),) if scores else ()


def _check_space(scene: LanguageScene, encoder: TextEncoder) -> None:
    if scene.text_encoder and scene.text_encoder != encoder.name:
        raise ValueError(
            f"{scene.seq_id}: features live in {scene.text_encoder!r}, queries would be encoded with {encoder.name!r}"
        )


def _smooth(values: np.ndarray, half: int = 2) -> np.ndarray:
    if len(values) <= 1:
        return values
    return moving_average(values, 2 * half + 1)


def instantaneous_states(traj: ObjectTrajectory) -> list[str]:
    """``[T]`` state phrase of an object in each of its frames, from that moment of its track only.

    Vehicles: ``"stopped"`` below ``STOPPED_MPS``, ``"turning left"`` / ``"turning right"`` when the
    yaw rate (smoothed over five frames) exceeds ``TURN_RATE_DEG_S``, else ``"moving"``. Pedestrians:
    ``"standing"``, ``"walking across the road"`` when on the drivable area (map known), else ``"walking"``.
    """
    speed = traj.speed
    if traj.kind == "pedestrian":
        on_road = traj.facts.on_drivable if traj.facts is not None else np.zeros(len(traj), dtype=bool)
        return [
            "standing" if v < STOPPED_MPS else ("walking across the road" if road else "walking")
            for v, road in zip(speed, on_road)
        ]
    if len(traj) > 1:
        rate = np.rad2deg(_smooth(np.gradient(traj.heading, traj.t)))
    else:
        rate = np.zeros(1)
    out = []
    for v, r in zip(speed, rate):
        if v < STOPPED_MPS:
            out.append("stopped")
        elif r > TURN_RATE_DEG_S:
            out.append("turning left")
        elif r < -TURN_RATE_DEG_S:
            out.append("turning right")
        else:
            out.append("moving")
    return out


def frame_captions(scene: LanguageScene, log: SceneLog) -> dict[int, list[str]]:
    """``node_id -> distinct per-frame captions`` over the frames where the object is visible.

    Static objects (and objects without a track) get their appearance caption alone; nodes without a
    caption get none.
    """
    if log.seq_id != scene.seq_id:
        raise ValueError(f"log {log.seq_id!r} does not belong to scene {scene.seq_id!r}")
    trajs = log_trajectories(log, min_frames=1)  # builds the log's map context itself
    out: dict[int, list[str]] = {}
    for node in scene.nodes:
        if node.caption is None:
            continue
        base = node.caption.text
        traj = trajs.get(node.object_id)
        if traj is None:
            out[node.node_id] = [base]
            continue
        states = instantaneous_states(traj)
        rows = np.flatnonzero(traj.visible) if traj.visible.any() else np.arange(len(traj))
        out[node.node_id] = list(dict.fromkeys(f"{base} {states[r]}" for r in rows))
    return out


class FrameCaptionGrounder:
    """4D-LangSplat-like baseline: max over frames of ``cos(E5_query(text), E5_passage(frame caption))``.

    Args:
        text_encoder: the encoder of the scenes' space.
        logs: ``seq_id -> SceneLog`` of the scenes to be queried (tracks and map).
    """

    name = "4D-LangSplat-like"

    def __init__(self, text_encoder: TextEncoder, logs: Mapping[str, SceneLog]) -> None:
        self.text_encoder = text_encoder
        self.logs = dict(logs)
        self._cache: dict[str, tuple[list[int], np.ndarray, np.ndarray]] = {}

    def _features(self, scene: LanguageScene) -> tuple[list[int], np.ndarray, np.ndarray]:
        """``(node ids [N], caption embeddings [M, D], owner row [M])`` of a scene (cached by sequence)."""
        key = f"{scene.seq_id}/{scene.scene_hash}"
        if key not in self._cache:
            if scene.seq_id not in self.logs:
                raise KeyError(f"FrameCaptionGrounder has no log for {scene.seq_id!r}")
            captions = frame_captions(scene, self.logs[scene.seq_id])
            ids = list(captions)
            texts = [c for nid in ids for c in captions[nid]]
            owner = np.array([i for i, nid in enumerate(ids) for _ in captions[nid]], dtype=np.int64)
            emb = (self.text_encoder.encode_passages(texts) if texts
                   else np.zeros((0, self.text_encoder.dim), np.float32))
            self._cache[key] = (ids, emb, owner)
        return self._cache[key]

    def scores(self, scene: LanguageScene, text: str) -> dict[int, float]:
        """``node_id -> max over frames`` of the caption cosine."""
        _check_space(scene, self.text_encoder)
        ids, emb, owner = self._features(scene)
        if not ids:
            return {}
        q = self.text_encoder.encode_queries([text])[0]
        sims = emb @ q
        best = np.full(len(ids), -np.inf)
        np.maximum.at(best, owner, sims)
        return {nid: float(s) for nid, s in zip(ids, best)}

    def ground(self, scene: LanguageScene, text: str) -> tuple[int, ...]:
        return _best_node(self.scores(scene, text))


class EngineGrounder:
    """Adapter: ``engine.ground(scene, text).node_ids`` as a tuple of ints (for ``QueryEngine``)."""

    def __init__(self, engine: Any, name: str = "ours") -> None:
        self.engine = engine
        self.name = name

    def ground(self, scene: LanguageScene, text: str) -> tuple[int, ...]:
        return tuple(int(n) for n in self.engine.ground(scene, text).node_ids)


__all__ = [
    "AppearanceOnlyGrounder",
    "EngineGrounder",
    "FrameCaptionGrounder",
    "frame_captions",
    "instantaneous_states",
]
