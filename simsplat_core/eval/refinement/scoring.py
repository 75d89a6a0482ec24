"""Per-agent failures of a scenario for the ``motion`` table and its outcomes table: how many agents collide /
leave the road, and for each failing agent what happened (so failures can be inspected).

    agents = score_agents(states, map_ctx, baseline=log)
    agents.collided, agents.offroad          # counts over every agent of ``states``
    agents.details       # ("car_3 [refined vehicle]: collision with ego [log vehicle] from 4.2 s", ...)

Collisions count every pair (``metrics.collision_steps`` with ``count_log_pairs``: in a rollout or an edited
scenario every agent's path may have changed); given ``baseline`` (the log on the same steps), a pair that
overlapped there at that step is the log's and does not count. Off-road and kinematic checks are
``scenario.metrics``'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.metrics import collision_steps, kinematic_violations, offroad_steps, validate_agents
from simsplat_core.scenario.rollout_metrics import unchanged_rows


@dataclass(frozen=True)
class AgentScores:
    """Per-agent failures of one scenario.

    Attributes:
        agents: agents checked (every row).
        collided: agents that collide with anyone at some step.
        offroad: agents that leave the road at some step.
        details: one line per failing agent (row order): ``"<id> [<source> <category>]: <what> at <t> s; ..."``.
    """

    agents: int
    collided: int
    offroad: int
    details: tuple[str, ...] = ()


def _who(states: AgentStates, row: int) -> str:
    return f"{states.object_ids[row]} [{states.sources[row]} {states.categories[row]}]"


def score_agents(states: AgentStates, context: MapContext, baseline: AgentStates | None = None) -> AgentScores:
    """The :class:`AgentScores` of every agent of ``states`` (module docstring)."""
    rows = np.arange(states.num_agents)
    coll = collision_steps(states, rows, baseline, count_log_pairs=True)
    hit = np.asarray(coll.pairs.any(axis=(1, 2)), dtype=bool)  # [A]
    own = ~unchanged_rows(states, rows, baseline)  # [A] the log's own off-road / kinematics are not failures
    off = offroad_steps(states, context, rows) & own[:, None]  # [A, T]
    kin = np.asarray(kinematic_violations(states, rows=rows).any(axis=1), dtype=bool) & own  # [A]
    failed = np.flatnonzero(hit | off.any(axis=1) | kin)
    kin_detail = {}
    if kin.any():
        report = validate_agents(states, context, np.flatnonzero(kin))
        kin_detail = {a.object_id: (a.kinematic_step, a.kinematic_detail) for a in report.agents}
    details = []
    for r in failed:
        parts = []
        if hit[r]:
            step = int(np.flatnonzero(coll.pairs[r].any(axis=0))[0])
            others = np.flatnonzero(coll.pairs[r].any(axis=1))
            parts.append(f"collision with {', '.join(_who(states, int(o)) for o in others)} from "
                         f"{states.times[step]:.1f} s")
        if off[r].any():
            parts.append(f"off-road from {states.times[int(np.flatnonzero(off[r])[0])]:.1f} s "
                         f"({int(off[r].sum())} steps)")
        if kin[r]:
            first, what = kin_detail.get(states.object_ids[r], (None, ""))
            parts.append(f"kinematic ({what})" + (f" from {states.times[first]:.1f} s" if first is not None else ""))
        details.append(f"{_who(states, int(r))}: {'; '.join(parts)}")
    return AgentScores(agents=states.num_agents, collided=int(hit.sum()), offroad=int(off.any(axis=1).sum()),
                       details=tuple(details))


__all__ = ["AgentScores", "score_agents"]
