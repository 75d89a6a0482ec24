"""The rule-based judge on edits of the editing tests' synthetic scene: clean edits pass; a collision, an unchanged
target, an absent removal, an object nobody sees and blank renders fail with the parameter changes that fix them;
and the judge request built from an edit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.editing.apply import Editor, apply_edit
from simsplat_core.editing.commands import EditProgram
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.options import DEFAULT_OPTIONS
from simsplat_core.editing.result import EditedScene
from simsplat_core.mining import (
    AgentTrajectory,
    JudgeRequest,
    RuleBasedVLMClient,
    ValidationFailure,
    judge_request_from_edit,
    visible_pixels_of,
)
from simsplat_core.mining.judge_input import targets_of
from simsplat_core.mining.rule_judge import JudgeConfig, motion_of, render_problem
from simsplat_core.mining.vlm_prompts import judge_text

#: Everyone but the edited agents replays the log (so a stop can make the traffic behind crash into it).
NO_REFINE = dataclasses.replace(DEFAULT_OPTIONS, refinement="none")
RENDER = np.random.default_rng(0).random((64, 96, 3))  # a non-degenerate view
BRAKE = "Make the blue SUV in the oncoming lane slam on the brakes."


@pytest.fixture(scope="module")
def client() -> RuleBasedVLMClient:
    return RuleBasedVLMClient()


@pytest.fixture(scope="module")
def editor(ctx: EditContext) -> Editor:
    return Editor(ctx)


@pytest.fixture(scope="module")
def braking(editor: Editor) -> EditedScene:
    return editor.edit(BRAKE)


def _parameters(request: JudgeRequest, client: RuleBasedVLMClient) -> set[str]:
    return {s.parameter for s in client.judge(request).suggestions}


@pytest.mark.parametrize("prompt", [
    BRAKE,
    "Remove the white van.",
    "Add a car in the left lane 15 m ahead and make it cut in to the right.",
    "Make the parked white hatchback reverse.",
    "Make the red sedan turning right take a left.",
    "Make the pedestrian in a white top and black pants jaywalk across the road.",
    "Put 4 orange cones in our lane 30 m ahead.",
    "Make the blue SUV in the oncoming lane go 10 km/h slower.",
])
def test_clean_edits_are_accepted(prompt: str, editor: Editor, client: RuleBasedVLMClient) -> None:
    edited = editor.edit(prompt)
    assert edited.validation.ok
    verdict = client.judge(judge_request_from_edit(edited, [RENDER], RENDER))
    assert verdict.follows_prompt and verdict.plausibility == 4, verdict.reasons
    assert not verdict.suggestions and any("requested change present" in r or "removed" in r for r in verdict.reasons)


def test_a_collision_lowers_plausibility_and_asks_for_a_later_start_or_lower_speed(ctx: EditContext,
                                                                                    client: RuleBasedVLMClient) -> None:
    program = EditProgram.model_validate({"prompt": "make the red sedan stop", "commands": [
        {"op": "modify", "target": {"object_id": "veh_01"}, "behaviour": {"stop": {}}}]})
    crashed = apply_edit(ctx, program, NO_REFINE)  # the blue SUV behind it replays its log into it
    assert not crashed.validation.ok
    request = judge_request_from_edit(crashed, [RENDER], RENDER)
    assert request.failures and request.failures[0].kind == "collision" and request.failures[0].other_id
    verdict = client.judge(request)
    assert verdict.follows_prompt  # it does stop ...
    assert verdict.plausibility <= 2  # ... into a crash
    changes = {(s.parameter, s.value) for s in verdict.suggestions}
    assert ("start_time", "2 s later") in changes and any(p == "speed" for p, _ in changes)


def test_injected_collision_and_off_road_failures(braking: EditedScene, client: RuleBasedVLMClient) -> None:
    request = judge_request_from_edit(braking, [RENDER], RENDER)
    hit = dataclasses.replace(request, failures=(ValidationFailure("veh_05", "collision", 12, "veh_01", "crash"),))
    verdict = client.judge(hit)
    assert verdict.plausibility == 2 and "crash" in verdict.reasons
    assert {"start_time", "speed"} <= {s.parameter for s in verdict.suggestions}
    off = dataclasses.replace(request, failures=(ValidationFailure("veh_05", "offroad", 20, text="off the road"),))
    assert _parameters(off, client) == {"offset", "anchor"} and client.judge(off).plausibility == 2
    both = dataclasses.replace(request, failures=(*hit.failures, *off.failures))
    assert client.judge(both).plausibility == 1


def test_a_pedestrian_told_to_run_is_not_asked_to_slow_down_after_a_collision(editor: Editor,
                                                                              client: RuleBasedVLMClient) -> None:
    edited = editor.edit("Make the pedestrian in a white top and black pants run.")
    request = judge_request_from_edit(edited, [RENDER], RENDER)
    (runner,) = request.command_targets[0]
    hit = dataclasses.replace(request, failures=(ValidationFailure(runner, "collision", 12, "veh_01", "crash"),))
    changes = {s.parameter for s in client.judge(hit).suggestions}
    assert "start_time" in changes and "speed" not in changes  # running slower is not running
    moving = [t.object_id for t in request.trajectories if t.object_id not in (runner, "ego")
              and float(np.nanmax(np.linalg.norm(np.diff(t.xy, axis=0), axis=1), initial=0.0)) > 0.2]
    other = dataclasses.replace(request, failures=(ValidationFailure(moving[0], "collision", 12, runner, "crash"),))
    assert "speed" not in {s.parameter for s in client.judge(other).suggestions}  # no command's agent to slow


def test_an_unchanged_target_does_not_follow_the_prompt(braking: EditedScene, client: RuleBasedVLMClient) -> None:
    request = judge_request_from_edit(braking, [RENDER], RENDER)
    unchanged = [dataclasses.replace(t, xy=request.log_trajectory(t.object_id).xy)  # type: ignore[union-attr]
                 if t.is_target else t for t in request.trajectories]
    verdict = client.judge(dataclasses.replace(request, trajectories=unchanged))
    assert not verdict.follows_prompt and verdict.plausibility == 3
    assert any("does not brake" in r for r in verdict.reasons)
    assert [s.parameter for s in verdict.suggestions] == ["speed"]


def test_a_removed_object_still_there_and_a_missing_insert_fail(editor: Editor, client: RuleBasedVLMClient) -> None:
    removal = judge_request_from_edit(editor.edit("Remove the white van."), [RENDER], RENDER)
    van = removal.trajectory("veh_02")
    assert van is not None and not van.present.any()  # removed: all NaN
    kept = [dataclasses.replace(t, xy=removal.log_trajectory("veh_02").xy) if t.object_id == "veh_02" else t  # type: ignore[union-attr]
            for t in removal.trajectories]
    verdict = client.judge(dataclasses.replace(removal, trajectories=kept))
    assert not verdict.follows_prompt and "still in the scene" in verdict.reasons[0]
    cone = editor.edit("Put an orange traffic cone in our lane 30 m ahead.")
    insert = judge_request_from_edit(cone, [RENDER], RENDER)
    gone = [t for t in insert.trajectories if not t.is_target]
    verdict = client.judge(dataclasses.replace(insert, trajectories=gone))
    assert not verdict.follows_prompt and "nothing was inserted" in verdict.reasons[0]


def test_blank_renders_and_invisible_targets_fail(braking: EditedScene, client: RuleBasedVLMClient) -> None:
    blank = judge_request_from_edit(braking, [RENDER, np.zeros((64, 96, 3), np.uint8)], RENDER)
    verdict = client.judge(blank)
    assert not verdict.follows_prompt and verdict.plausibility == 2
    assert any("render 1 blank" in r for r in verdict.reasons) and _parameters(blank, client) == {"other"}
    unseen = judge_request_from_edit(braking, [RENDER], RENDER, visible_pixels={"veh_05": 4})
    verdict = client.judge(unseen)
    assert not verdict.follows_prompt and verdict.plausibility == 3
    assert _parameters(unseen, client) == {"asset", "offset"}
    seen = judge_request_from_edit(braking, [RENDER], RENDER, visible_pixels={"veh_05": 400})
    assert client.judge(seen).follows_prompt


def test_render_problems() -> None:
    cfg = JudgeConfig()
    assert render_problem(np.full((8, 8, 3), 128, np.uint8), cfg) == "blank"
    holes = np.zeros((8, 8, 3))
    holes[:2] = np.random.default_rng(1).random((2, 8, 3))
    assert render_problem(holes, cfg) == "holes"
    assert render_problem(RENDER, cfg) is None


def test_the_judge_request_of_an_edit(braking: EditedScene, editor: Editor) -> None:
    request = judge_request_from_edit(braking, [RENDER], RENDER)
    assert request.prompt == BRAKE and request.program is not None and request.command_targets == (("veh_05",),)
    target = request.trajectory("veh_05")
    assert target is not None and target.is_target and target.source == "edited" and target.heading is not None
    log = request.log_trajectory("veh_05")
    assert log is not None and log.source == "log"
    assert motion_of(target, request.dt_s).end_speed < motion_of(log, request.dt_s).end_speed
    others = [t for t in request.trajectories if not t.is_target]
    assert others and {t.source for t in others} <= {"log", "refined"}
    assert request.validation[0].endswith("no collision, no off-road, kinematics within bounds")
    assert '"op": "modify"' in request.command_json
    text = judge_text(request)  # what the HTTP client sends: the structured facts do not get in its way
    assert "Executed edit program" in text and "veh_05 [target] vehicle, edited" in text
    cones = editor.edit("Put 4 orange cones in our lane 30 m ahead.")
    assert len(targets_of(cones)[0]) == 4


def test_visible_pixels_count_node_ids(braking: EditedScene) -> None:
    states = braking.states
    node = int(states.node_ids[states.index("veh_05")])
    maps = [np.full((4, 6), -1, np.int32), np.full((4, 6), -1, np.int32)]
    maps[0][:2, :3] = node
    maps[1][0, 0] = node
    assert visible_pixels_of(maps, states, ["veh_05", "ego", "nobody"]) == {"veh_05": 7, "ego": 0, "nobody": 0}


def test_a_request_without_program_is_judged_on_the_targets_alone(client: RuleBasedVLMClient) -> None:
    xy = np.stack([np.linspace(0, 10, 11), np.zeros(11)], axis=1)
    moved = AgentTrajectory("car", "vehicle", "edited", xy + [0.0, 3.0], is_target=True)
    log = AgentTrajectory("car", "vehicle", "log", xy)
    assert client.judge(JudgeRequest("shift the car", [RENDER], RENDER, [moved], before=[log])).follows_prompt
    same = dataclasses.replace(moved, xy=xy)
    verdict = client.judge(JudgeRequest("shift the car", [RENDER], RENDER, [same], before=[log]))
    assert not verdict.follows_prompt and verdict.suggestions[0].parameter == "speed"
    assert not client.judge(JudgeRequest("shift the car", [RENDER], RENDER)).follows_prompt
