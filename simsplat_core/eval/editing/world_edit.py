"""The synthetic world carries out the same edit itself: ground truth for edit fidelity and visibility.

Given the agents before and after an edit (``AgentStates``) and the looks of inserted objects, the
world (a copy; the original is never changed)

* drops removed agents;
* drives moved agents along their edited trajectories (``traj``: ``xy``, ``heading``, ``speed`` and the
  walked distance ``s`` that times a pedestrian's gait);
* adds a world-native agent for every inserted object on its trajectory: a vehicle of the asset's body
  style, box and colour, a pedestrian with the source pedestrian's build, skin, hair and gait (the
  asset's clothing colours), a static object of the asset's kind -- so the world renders what the
  editor should have drawn;
* redraws replaced agents with the replacing asset's look on the same trajectory.

Static objects are drawn with the procedural kinds' meshes (``editing.assets.procedural.static_kind_mesh``, the
world's own meshes for the world's kinds), from which the bank's procedural Gaussians were made. A look the
world cannot build (an unknown kind) is drawn by the closest kind of similar size and reported as not native:
visibility checks still use it, fidelity leaves it out.

Steps where an agent does not exist (``AgentStates.valid`` false) place it far away (``AWAY_M``), where no
camera sees it. Instance ids of the edited world are positions in its agent list plus one
(``World.instance_id``); :class:`EditedWorld` maps object ids to them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from simsplat_core.color_names import DISPLAY_RGB
from simsplat_core.editing.assets.procedural import STATIC_KINDS as PROCEDURAL_KINDS
from simsplat_core.editing.assets.procedural import static_kind_mesh
from simsplat_core.eval.editing.observation import AssetLook, state_changes
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.world import World
from simsplat_core.world import behaviors as bh
from simsplat_core.world.agents import WALK_SWING, Agent
from simsplat_core.world.mesh import Mesh
from simsplat_core.world.palette import HAIR_COLORS, SKIN_TONES, STATIC_KINDS, VEHICLE_KIND_BY_NAME

#: Where an agent goes at steps it does not exist (metres from the origin).
AWAY_M = 1.0e5
#: Rendered output of one camera: ``(name, K, cam_to_world, image, depth, instance, ground)``.
CameraRender = tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True, eq=False)
class EditedWorld:
    """The world after the edit.

    Attributes:
        world: a new ``World`` (agents replaced; layout, ego and scenery shared with the original).
        instance: ``object id -> instance id`` in the edited world's renders.
        native: object ids drawn as world-native equivalents (every kept or moved agent; inserted and
            replacing ones whose look the world can build).
        notes: what was drawn by a stand-in, for reports.
    """

    world: World
    instance: dict[str, int]
    native: frozenset[str]
    notes: tuple[str, ...] = ()

    def render(self, frame: int) -> list[CameraRender]:
        return self.world.render(frame)


def trajectory_of(states: AgentStates, row: int, s0: float = 0.0) -> dict[str, np.ndarray]:
    """A world ``traj`` dict from one agent of ``states`` (``[T]`` steps; absent steps far away)."""
    valid = states.valid[row]
    xy = np.where(valid[:, None], states.xy[row], AWAY_M)
    step = np.linalg.norm(np.diff(states.xy[row], axis=0), axis=1) * (valid[1:] & valid[:-1])
    return {"xy": xy.astype(np.float64), "heading": states.heading[row].astype(np.float64),
            "speed": np.abs(states.speed[row]).astype(np.float64),
            "s": s0 + np.concatenate([[0.0], np.cumsum(step)])}


def _rgb(color: str) -> tuple[float, float, float]:
    if color not in DISPLAY_RGB:
        raise ValueError(f"colour {color!r} has no display RGB in color_names")
    return DISPLAY_RGB[color]


def _static_mesh(look: AssetLook) -> tuple[Mesh, bool]:
    """The mesh of a static look: its procedural kind's mesh (the world's own for the world's kinds), else a
    stand-in -- the world kind nearest in size -- with ``native`` false."""
    rgb = _rgb(look.color) if look.color in DISPLAY_RGB else DISPLAY_RGB["orange"]
    size = tuple(float(v) for v in look.size)
    if look.subtype in PROCEDURAL_KINDS:
        return static_kind_mesh(look.subtype, size, rgb), True  # type: ignore[arg-type]
    nearest = min(STATIC_KINDS, key=lambda k: float(np.linalg.norm(np.asarray(STATIC_KINDS[k][1]) - np.asarray(size))))
    return static_kind_mesh(nearest, size, rgb), False  # type: ignore[arg-type]


def native_agent(look: AssetLook, object_id: str, traj: dict[str, np.ndarray],
                 source: Agent | None = None) -> tuple[Agent, bool]:
    """A world agent that looks like ``look`` on ``traj``; ``(agent, native)`` (``native`` false: a stand-in).

    ``source`` is the ground-truth agent the asset was cut out of (its build, skin, hair and gait).
    """
    motion = bh.stand(np.asarray(traj["xy"][0], float), float(traj["heading"][0]))
    size = tuple(float(v) for v in look.size)
    if look.category == "vehicle":
        native = look.subtype in VEHICLE_KIND_BY_NAME and look.color in DISPLAY_RGB
        subtype = look.subtype if look.subtype in VEHICLE_KIND_BY_NAME else "sedan"
        rgb = _rgb(look.color) if look.color in DISPLAY_RGB else DISPLAY_RGB["gray"]
        agent = Agent("vehicle", subtype, size, motion, traj, {"color": look.color}, {"rgb": rgb})  # type: ignore[arg-type]
    elif look.category == "pedestrian":
        native = source is not None and source.category == "pedestrian"
        moving = float(np.max(traj["speed"])) > 0.3
        base = dict(source.look) if native and source is not None else {
            "skin": SKIN_TONES[0], "hair": HAIR_COLORS[0], "swing": WALK_SWING if moving else 0.0,
            "stride": 1.35 * size[2] / 1.75, "phase0": 0.0}
        lower = look.lower or (source.appearance.get("lower_color") if source is not None else None) or "gray"
        base.update(upper=_rgb(look.color) if look.color in DISPLAY_RGB else DISPLAY_RGB["gray"],
                    lower=_rgb(lower) if lower in DISPLAY_RGB else DISPLAY_RGB["gray"])
        agent = Agent("pedestrian", "pedestrian", size, motion, traj,  # type: ignore[arg-type]
                      {"upper_color": look.color, "lower_color": lower}, base)
    else:
        mesh, native = _static_mesh(look)
        category = STATIC_KINDS[look.subtype][0] if look.subtype in STATIC_KINDS else "static"
        # the mesh cache filled in up front: the world builds meshes only of its own catalogue
        agent = Agent(category, look.subtype, size, motion, traj, {"color": look.color},  # type: ignore[arg-type]
                      {"rgb": DISPLAY_RGB.get(look.color, DISPLAY_RGB["orange"])}, _mesh=mesh)
    agent.object_id = object_id
    return agent, native


def edit_world(world: World, before: AgentStates, after: AgentStates, looks: Mapping[str, AssetLook],
               source_agent: Callable[[AssetLook], Agent | None] = lambda look: None) -> EditedWorld:
    """The world with the edit that turned ``before`` into ``after`` (module docstring).

    ``looks`` holds the look of every added object and of every redrawn (replaced) one; ``source_agent``
    finds the ground-truth agent an asset was cut out of (``None`` when unknown).

    Raises:
        ValueError: the states do not cover the world's frames, or an added object has no look.
    """
    if before.num_steps != len(world.times) or not np.array_equal(after.frame_idx, np.arange(len(world.times))):
        raise ValueError(f"edit_world: states cover frames {after.frame_idx[:3]}..., the world has "
                         f"{len(world.times)} frames from 0")
    changes = state_changes(before, after)
    missing = [o for o in (*changes.added, *changes.redrawn) if o not in looks]
    if missing:
        raise ValueError(f"edit_world: no look for added / replaced objects {missing}")
    agents: list[Agent] = []
    native: set[str] = set()
    notes: list[str] = []
    removed = set(changes.removed)
    by_id = {a.object_id: a for a in world.agents}
    for agent in world.agents:
        oid = agent.object_id
        if oid in removed:
            continue
        if oid in changes.redrawn:
            new, ok = native_agent(looks[oid], oid, trajectory_of(after, after.index(oid)), source_agent(looks[oid]))
        elif oid in changes.moved:
            row = after.index(oid)
            new, ok = dataclasses.replace(agent, traj=trajectory_of(after, row, float(agent.traj["s"][0]))), True
        else:
            new, ok = agent, True
        agents.append(new)
        if ok:
            native.add(oid)
        else:
            notes.append(f"{oid} drawn as a {new.subtype} stand-in")
    for oid in changes.added:
        look = looks[oid]
        new, ok = native_agent(look, oid, trajectory_of(after, after.index(oid)), source_agent(look))
        agents.append(new)
        if ok:
            native.add(oid)
        else:
            notes.append(f"{oid} ({look.subtype}) drawn as a {new.subtype} stand-in")
    unknown = [o for o in (*changes.moved, *changes.redrawn) if o != EGO_ID and o not in by_id]
    if unknown:
        raise ValueError(f"edit_world: moved objects {unknown} are not agents of the world")
    edited = dataclasses.replace(world, agents=agents)
    return EditedWorld(edited, {a.object_id: k + 1 for k, a in enumerate(agents)}, frozenset(native), tuple(notes))


__all__ = ["AWAY_M", "CameraRender", "EditedWorld", "edit_world", "native_agent", "trajectory_of"]
