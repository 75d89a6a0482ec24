"""Baseline predictors of the ``MotionPredictor`` protocol: the floor of the motion table and test doubles.

* :class:`LogReplayPredictor` (``"log"``): every agent replays its log (the request's states as given).
* :class:`ConstantVelocityPredictor` (``"constant-velocity"``): each free agent observed at the last history
  step keeps the velocity of its last ``window_s`` of history (box-centre displacement; the stored speed
  along the heading when the history is one step) and its heading, and stays valid to the end. Free
  agents not observed at the last history step are replayed (named in ``Rollout.replayed``).

Neither reads the map; fixed rows are returned unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from simsplat_core.motion.predictor import Rollout, RolloutRequest

#: ``Rollout.replayed`` reason of agents without a state at the last history step.
NOT_OBSERVED = "not observed at the last history step"


@dataclass
class LogReplayPredictor:
    """Returns the log: every agent's logged states (the request's ``states`` unchanged)."""

    name: str = "log"

    def rollout(self, request: RolloutRequest) -> Rollout:
        return Rollout(states=request.states, replayed={}, predictor=self.name)


@dataclass
class ConstantVelocityPredictor:
    """Extrapolates each free agent from its last history step at constant velocity (module docstring).

    Attributes:
        window_s: history span the velocity is measured over (the last step and the earliest valid step of
            the same run no more than ``window_s`` before it).
    """

    name: str = "constant-velocity"
    window_s: float = 0.2

    def rollout(self, request: RolloutRequest) -> Rollout:
        s = request.states
        last = request.start_step - 1
        future = np.arange(request.start_step, s.num_steps)
        xy, heading, speed = s.xy.copy(), s.heading.copy(), s.speed.copy()
        z, valid = s.z.copy(), s.valid.copy()
        sources = list(s.sources)
        replayed: dict[str, str] = {}
        for row in request.free_rows:
            r = int(row)
            if not s.valid[r, last]:
                replayed[s.object_ids[r]] = NOT_OBSERVED
                continue
            first = last
            while first > 0 and s.valid[r, first - 1] and s.times[last] - s.times[first - 1] <= self.window_s + 1e-9:
                first -= 1
            unit = np.array([np.cos(s.heading[r, last]), np.sin(s.heading[r, last])])
            if first < last:
                velocity = (s.xy[r, last] - s.xy[r, first]) / (s.times[last] - s.times[first])
            else:
                velocity = s.speed[r, last] * unit
            dt = s.times[future] - s.times[last]  # [F]
            xy[r, future] = s.xy[r, last] + dt[:, None] * velocity
            z[r, future] = s.z[r, last]
            heading[r, future] = s.heading[r, last]
            speed[r, future] = float(velocity @ unit)
            valid[r, future] = True
            sources[r] = "refined"
        states = replace(s, xy=xy, z=z, heading=heading, speed=speed, valid=valid, sources=tuple(sources))
        return Rollout(states=states, replayed=replayed, predictor=self.name)


__all__ = ["NOT_OBSERVED", "ConstantVelocityPredictor", "LogReplayPredictor"]
