"""The traffic's reaction to an edit, on the edit's working copy: refine, then give reacting nodes new tracks.

``react(draft, "full")`` runs ``motion.refine.refine`` on the draft's agents and writes the result back into the
draft: ``draft.states`` (reacting agents with ``source == "refined"``), a new pose track for the node of every
agent whose path changed (stored nodes through ``Draft.set_track``, inserted nodes by replacing their
``AddedNode`` track; a pedestrian's gait is retimed to its new path) and ``draft.refinement``. Agents without a
node (the ego, unreconstructed tracks) only change in the states.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from simsplat_core.editing.draft import Draft
from simsplat_core.editing.ops import track_from_states
from simsplat_core.motion.refine import refine

logger = logging.getLogger(__name__)

#: A path counts as changed by refinement when a box centre moved by more than this, metres.
MOVED_M = 1e-3


def react(draft: Draft, mode: str, ego_reacts: bool = False) -> None:
    """Refine the draft's traffic in ``mode`` (``motion.refine.REFINE_MODES``; the ego too with ``ego_reacts``) and
    update its nodes in place."""
    before = draft.states
    refinement = refine(before, draft.ctx.motion_map, draft.ctx.motion_predictor(), mode, original=draft.ctx.states,
                        ego_reacts=ego_reacts)
    after = refinement.states
    added = {a.node_id: k for k, a in enumerate(draft.added)}
    for row, node_id in enumerate(after.node_ids.tolist()):
        moved = np.abs(after.xy[row] - before.xy[row]).max(initial=0.0) > MOVED_M
        if node_id < 0 or not (moved or (after.valid[row] != before.valid[row]).any()):
            continue
        track = track_from_states(after, row)
        if node_id in added:
            k = added[node_id]
            draft.added[k] = dataclasses.replace(draft.added[k], track=track, arc_length=None)
        else:  # a stored node that reacted (or, in single-agent mode, an edited one the predictor adjusted)
            draft.set_track(node_id, track)
    draft.states = after
    draft.refinement = refinement
