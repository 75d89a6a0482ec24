"""Interaction-heavy edit prompts for the motion benchmark: edits that other agents must react to.

Written from a synthetic scene's ground truth (``eval.editing.truth.SceneTruth``), in varied wording, each
about a well-visible object that a description singles out (``eval.editing.references.object_phrase``, which
brings its own article: "the blue car taking a right"):

* ``sudden_stop``: a moving vehicle with another vehicle following it in its lane brakes hard / stops;
* ``cut_in``: a moving vehicle changes into a neighbouring lane where another vehicle drives just behind;
* ``jaywalker``: a pedestrian is inserted crossing the road in front of a moving vehicle;
* ``lane_obstacle``: a stopped vehicle or a row of cones is inserted in a moving vehicle's lane ahead of it;
* ``blocked_crosswalk``: a barrier is put on the crosswalk a walking pedestrian is heading for.

Only situations where someone other than the ego must react are written: the ego replays its log (its cameras
render the scene), so an edit in front of the ego tests the editor's own checks, not refinement.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.eval.editing.references import object_phrase
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.eval.editing.wording import pick
from simsplat_core.geometry import wrap_angle
from simsplat_core.scenario.geometry import points_in_polygon
from simsplat_core.world.agents import Agent

#: Kinds of interaction prompts, in table order.
INTERACTION_KINDS: tuple[str, ...] = ("sudden_stop", "cut_in", "jaywalker", "lane_obstacle", "blocked_crosswalk")
#: A vehicle counts as moving from this speed at the first frame, m/s.
MOVING_MPS = 3.0
#: A follower is behind within this distance, metres (and within ``SAME_LANE_M`` of the leader's line).
FOLLOW_RANGE_M = (4.0, 35.0)
SAME_LANE_M = 1.5
#: Headings within this of each other count as the same direction, degrees.
SAME_DIRECTION_DEG = 30.0
#: Lateral offset range of a vehicle in a neighbouring lane, metres; and how far behind it may be.
NEIGHBOUR_LANE_M = (2.2, 4.8)
NEIGHBOUR_BEHIND_M = (0.0, 25.0)
#: A walking pedestrian heads for a crosswalk within this many metres along its heading.
CROSSWALK_AHEAD_M = 12.0

FORMS: dict[str, tuple[str, ...]] = {
    "sudden_stop": (
        "{T} brakes hard.", "Make {T} stop suddenly.", "Have {T} slam on the brakes.",
        "{T} should come to an abrupt stop.", "Let {T} do an emergency stop.",
    ),
    "cut_in": (
        "{T} cuts into the {side} lane.", "Make {T} change lanes to the {side}.",
        "Have {T} merge into the {side} lane.", "{T} should move over to the {side} lane.",
    ),
    "jaywalker": (
        "A pedestrian jaywalks across the road {d} m in front of {T}.",
        "Add a person crossing the street {d} m ahead of {T}.",
        "Insert a jaywalker {d} metres in front of {T}.",
        "Put a pedestrian walking across the road {d} m in front of {T}.",
    ),
    "lane_obstacle": (
        "Insert a stopped truck {d} m in front of {T}.", "Park a white van {d} m ahead of {T}.",
        "Put a row of cones {d} m in front of {T}.", "Place a broken-down car {d} metres ahead of {T}.",
        "Add a barrier {d} m in front of {T}.",
    ),
    "blocked_crosswalk": (
        "Put a barrier on the crosswalk.", "Block the crosswalk with a road barrier.",
        "Place a construction barrier on the pedestrian crossing.",
    ),
}


@dataclass(frozen=True)
class InteractionPrompt:
    """One interaction prompt: ``prompt_id`` ``"<seq_id>/interaction/<kind>/<n>"``, its words and the object it
    is about (``""`` when none)."""

    prompt_id: str
    seq_id: str
    kind: str
    text: str
    object_id: str


def _rng(seed: int, seq_id: str) -> np.random.Generator:
    return np.random.default_rng([seed, zlib.crc32(seq_id.encode()), zlib.crc32(b"interaction")])


def _relative(agent: Agent, other_xy: np.ndarray, frame: int = 0) -> tuple[float, float]:
    """``(along, left)`` of ``other_xy [2]`` in ``agent``'s frame at ``frame``, metres."""
    h = float(agent.traj["heading"][frame])
    d = np.asarray(other_xy, np.float64) - agent.traj["xy"][frame]
    return float(d[0] * np.cos(h) + d[1] * np.sin(h)), float(-d[0] * np.sin(h) + d[1] * np.cos(h))


def _same_direction(a: Agent, b: Agent, frame: int = 0) -> bool:
    diff = abs(float(wrap_angle(a.traj["heading"][frame] - b.traj["heading"][frame])))
    return diff <= np.deg2rad(SAME_DIRECTION_DEG)


def _moving(agent: Agent) -> bool:
    return agent.category == "vehicle" and float(agent.traj["speed"][0]) >= MOVING_MPS


def _follower(truth: SceneTruth, leader: Agent) -> bool:
    """Another moving vehicle follows ``leader`` in its lane at the first frame."""
    for other in truth.world.agents:
        if other is leader or not _moving(other) or not _same_direction(leader, other):
            continue
        along, left = _relative(leader, other.traj["xy"][0])
        if -FOLLOW_RANGE_M[1] <= along <= -FOLLOW_RANGE_M[0] and abs(left) <= SAME_LANE_M:
            return True
    return False


def _neighbour_side(truth: SceneTruth, agent: Agent) -> str | None:
    """``"left"`` / ``"right"``: a moving vehicle drives just behind in that neighbouring lane."""
    for other in truth.world.agents:
        if other is agent or not _moving(other) or not _same_direction(agent, other):
            continue
        along, left = _relative(agent, other.traj["xy"][0])
        if -NEIGHBOUR_BEHIND_M[1] <= along <= NEIGHBOUR_BEHIND_M[0] and NEIGHBOUR_LANE_M[0] <= abs(left) \
                <= NEIGHBOUR_LANE_M[1]:
            return "left" if left > 0 else "right"
    return None


def _heading_for_crosswalk(truth: SceneTruth, agent: Agent) -> bool:
    """A walking pedestrian whose path reaches a crosswalk within ``CROSSWALK_AHEAD_M`` of its first position."""
    if agent.category != "pedestrian" or float(np.max(agent.traj["speed"])) < 0.5:
        return False
    xy = agent.traj["xy"]
    near = np.linalg.norm(xy - xy[0], axis=1) <= CROSSWALK_AHEAD_M
    crosswalks = [np.asarray(f.points, np.float64)[:, :2] for f in truth.log.map_features if f.kind == "crosswalk"]
    return any(bool(points_in_polygon(xy[near], poly).any()) for poly in crosswalks)


def scene_interactions(truth: SceneTruth, rng: np.random.Generator, per_kind: int = 2) -> list[InteractionPrompt]:
    """Up to ``per_kind`` prompts of each :data:`INTERACTION_KINDS` about one scene (fewer where the scene offers
    no such situation)."""
    drafts: dict[str, list[tuple[str, dict[str, str]]]] = {k: [] for k in INTERACTION_KINDS}
    for agent in truth.world.agents:
        if not truth.well_visible(agent.object_id):
            continue
        phrase = object_phrase(truth, agent.object_id, rng)
        if phrase is None:
            continue
        slot = {"T": phrase}
        if _moving(agent):
            if _follower(truth, agent):
                drafts["sudden_stop"].append((agent.object_id, slot))
            side = _neighbour_side(truth, agent)
            if side is not None:
                drafts["cut_in"].append((agent.object_id, {**slot, "side": side}))
            distance = str(int(round(float(np.clip(agent.traj["speed"][0] * 2.0, 12.0, 25.0)))))
            drafts["jaywalker"].append((agent.object_id, {**slot, "d": distance}))
            drafts["lane_obstacle"].append((agent.object_id, {**slot, "d": str(int(pick(rng, ("20", "25", "30"))))}))
        if _heading_for_crosswalk(truth, agent):
            drafts["blocked_crosswalk"].append((agent.object_id, slot))
    out: list[InteractionPrompt] = []
    for kind in INTERACTION_KINDS:
        options = drafts[kind]
        order = [int(i) for i in rng.permutation(len(options))][:per_kind]
        forms = FORMS[kind]
        for n, k in enumerate(order):
            object_id, slots = options[k]
            text = forms[int(rng.integers(len(forms)))].format(**slots)
            text = text[:1].upper() + text[1:]
            out.append(InteractionPrompt(f"{truth.seq_id}/interaction/{kind}/{n}", truth.seq_id, kind, text,
                                         object_id))
    return out


def build_interactions(truths: Sequence[SceneTruth], per_kind: int = 2, seed: int = 0) -> list[InteractionPrompt]:
    """Interaction prompts over every scene (``per_kind`` of each kind per scene at most)."""
    return [p for truth in truths for p in scene_interactions(truth, _rng(seed, truth.seq_id), per_kind)]


__all__ = ["FORMS", "INTERACTION_KINDS", "InteractionPrompt", "build_interactions", "scene_interactions"]
