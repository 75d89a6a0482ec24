"""The rule-based judge checks requested manoeuvres with the trajectory auto-labeller the editing benchmark uses
(``language.motion_labels`` on ``scenario.trajectory.agent_trajectory``), not its own thresholds, when the request
carries the labels (the mining loop always gives them)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.editing.apply import Editor
from simsplat_core.editing.draft import EditContext
from simsplat_core.language.motion_labels import label_trajectory
from simsplat_core.mining import RuleBasedVLMClient, judge_request_from_edit
from simsplat_core.mining.judge_input import targets_of
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.trajectory import agent_trajectory

RENDER = np.random.default_rng(0).random((64, 96, 3))  # a non-degenerate view
MANOEUVRES = {
    "Make the parked white hatchback reverse.": voc.REVERSING,
    "Make the red sedan turning right take a left.": voc.TURNING_LEFT,
    "Add a car in the left lane 15 m ahead and make it cut in to the right.": voc.CHANGING_LANE_RIGHT,
    "Make the pedestrian in a white top and black pants jaywalk across the road.": "crossing",
}


@pytest.fixture(scope="module")
def editor(ctx: EditContext) -> Editor:
    return Editor(ctx)


@pytest.mark.parametrize("prompt", list(MANOEUVRES))
def test_the_labelled_manoeuvre_is_accepted_and_a_contradicting_label_rejected(prompt: str, ctx: EditContext,
                                                                             editor: Editor) -> None:
    edited = editor.edit(prompt)
    request = judge_request_from_edit(edited, [RENDER], RENDER, labeller=(ctx.log.ego_poses, ctx.map_ctx))
    (target,) = [o for ids in targets_of(edited) for o in ids]
    row = edited.states.index(target)
    labelled = label_trajectory(agent_trajectory(edited.states, row, ctx.map_ctx), ctx.log.ego_poses, ctx.map_ctx)
    assert request.motion_labels == {target: labelled.motion}  # the benchmark's labeller, on the edited trajectory
    assert labelled.motion.startswith(MANOEUVRES[prompt])
    client = RuleBasedVLMClient()
    verdict = client.judge(request)
    assert verdict.follows_prompt and verdict.plausibility == 4, verdict.reasons

    # the same trajectories, but the labeller does not see the manoeuvre: the judge's own thresholds no longer decide
    unseen = dataclasses.replace(request, motion_labels={target: voc.GOING_STRAIGHT if labelled.motion !=
                                                         voc.GOING_STRAIGHT else voc.STOPPED})
    if "pedestrian" in prompt:
        unseen = dataclasses.replace(request, motion_labels={target: voc.WALKING_ALONG})
    rejected = client.judge(unseen)
    assert not rejected.follows_prompt and rejected.plausibility < 4
    assert any(f"{target}: labelled" in r for r in rejected.reasons) and rejected.suggestions
    assert client.judge(dataclasses.replace(request, motion_labels=None)).follows_prompt  # without labels: as before
