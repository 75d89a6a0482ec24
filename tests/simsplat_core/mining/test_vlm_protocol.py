"""The VLMClient protocol's values, the answer models' strict validation and the prompt text builders."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from pydantic import ValidationError

from simsplat_core.editing.commands import EditProgram
from simsplat_core.mining import (
    PARAMETERS,
    AgentTrajectory,
    Judgement,
    JudgeRequest,
    ParameterChange,
    ProposalRequest,
    SceneSummary,
    ValidationFailure,
)
from simsplat_core.mining.vlm_answers import (
    JudgementAnswer,
    ProposalAnswer,
    judgement_json_schema,
    proposal_json_schema,
    validate_proposal,
)
from simsplat_core.mining.vlm_prompts import judge_text, propose_text, trajectory_line, trajectory_lines

RGB = np.zeros((4, 6, 3), np.uint8)


def test_values_are_checked_and_sequences_become_tuples() -> None:
    request = ProposalRequest([RGB, RGB.astype(np.float32)], SceneSummary("s", ("a fact",)), count=3)
    assert isinstance(request.views, tuple) and len(request.views) == 2
    assert request.summary.lines == ("a fact",)
    with pytest.raises(ValueError, match=r"views\[1\] must be an \[H, W, 3\]"):
        ProposalRequest([RGB, np.zeros((4, 6))], SceneSummary("s"))
    with pytest.raises(ValueError, match="at least one image"):
        ProposalRequest([], SceneSummary("s"))
    with pytest.raises(ValueError, match="count"):
        ProposalRequest([RGB], SceneSummary("s"), count=0)
    with pytest.raises(ValueError, match="prompt is empty"):
        JudgeRequest(" ", [RGB], RGB)
    with pytest.raises(ValueError, match="renders must hold"):
        JudgeRequest("p", [], RGB)
    with pytest.raises(ValueError, match="bev"):
        JudgeRequest("p", [RGB], np.zeros((0, 4, 3)))
    with pytest.raises(ValueError, match=r"car-1 must be \[T, 2\]"):
        AgentTrajectory("car-1", "vehicle", "log", np.zeros((5, 3)))


@pytest.mark.parametrize("plausibility", [0, 5])
def test_a_judgement_keeps_plausibility_within_1_to_4(plausibility: int) -> None:
    with pytest.raises(ValueError, match=r"1\.\.4"):
        Judgement(follows_prompt=True, plausibility=plausibility, reasons=("ok",))


def test_parameter_changes_name_a_known_parameter() -> None:
    assert PARAMETERS == ("asset", "speed", "start_time", "offset", "anchor", "other")
    with pytest.raises(ValueError, match="parameter must be one of"):
        ParameterChange("colour", "red")  # type: ignore[arg-type]


def test_proposal_answers_are_strict() -> None:
    schema = proposal_json_schema(3)
    assert schema["properties"]["prompts"]["maxItems"] == 3 and schema["additionalProperties"] is False
    assert validate_proposal({"prompts": [" Remove the bus. "]}, 3).prompts == ["Remove the bus."]
    bad: dict[str, Any]
    for bad in ({"prompts": []}, {"prompts": ["  "]}, {"prompts": ["a", "b c d"]}, {"prompts": "Remove it."},
                {"prompts": ["Remove the bus."], "extra": 1}, {"prompts": ["one", "two", "three", "four"]}):
        with pytest.raises(ValidationError):
            validate_proposal(bad, 3)
    answer = ProposalAnswer(prompts=["Stop the van.", "stop  the VAN.", "Remove the van."])
    assert answer.unique_prompts() == ["Stop the van.", "Remove the van."]


def test_judgement_answers_are_strict() -> None:
    schema = judgement_json_schema()
    assert schema["properties"]["plausibility"]["minimum"] == 1 and schema["properties"]["plausibility"]["maximum"] == 4
    good: dict[str, Any] = {"follows_prompt": True, "plausibility": 4, "reasons": ["fine"]}
    assert JudgementAnswer.model_validate(good).to_judgement() == Judgement(True, 4, ("fine",), ())
    for bad in ({**good, "plausibility": 3.5}, {**good, "plausibility": "3"}, {**good, "follows_prompt": 1},
                {**good, "reasons": [""]}, {**good, "mood": "happy"},
                {**good, "suggestions": [{"parameter": "speed"}]}):
        with pytest.raises(ValidationError):
            JudgementAnswer.model_validate(bad)


def test_trajectory_lines_sample_positions_skip_absent_steps_and_cap_agents() -> None:
    xy = np.full((11, 2), np.nan)
    xy[2:] = np.stack([np.arange(9.0), np.zeros(9)], axis=1)  # present from step 2, 1 m per step
    line = trajectory_line(AgentTrajectory("ped-1", "pedestrian", "inserted", xy), dt_s=0.5, samples=3)
    assert line == ("- ped-1 pedestrian, inserted: t=1.0s (0.0, 0.0); t=3.0s (4.0, 0.0); t=5.0s (8.0, 0.0); "
                    "travelled 8.0 m, mean speed 2.0 m/s")
    absent = AgentTrajectory("car-9", "vehicle", "log", np.full((3, 2), np.nan))
    assert trajectory_line(absent, dt_s=0.1).endswith(": absent")
    agents = [AgentTrajectory(f"car-{i}", "vehicle", "log", np.zeros((2, 2))) for i in range(5)]
    agents.append(AgentTrajectory("car-t", "vehicle", "edited", np.zeros((2, 2)), is_target=True))
    lines = trajectory_lines(agents, dt_s=0.1, max_agents=3)
    assert [ln.split()[1] for ln in lines[:3]] == ["car-t", "car-0", "car-1"]
    assert lines[3] == "- ... and 3 more agent(s) not listed"


def test_request_texts_name_what_the_images_are() -> None:
    summary = SceneSummary("synth-7", ())
    assert "(no facts)" in propose_text(ProposalRequest([RGB], summary, count=2))
    text = judge_text(JudgeRequest("Remove the bus.", [RGB, RGB], RGB))
    assert "2 camera renders of the edited scene, then the bird's-eye view" in text
    assert "Executed edit program" not in text and text.count("(none given)") == 2


def test_the_structured_judge_facts_are_checked() -> None:
    program = EditProgram.model_validate({"prompt": "remove the bus", "commands": [
        {"op": "remove", "target": {"description": "the bus"}}]})
    request = JudgeRequest("remove the bus", [RGB], RGB, program=program, command_targets=[("bus_1",)],
                           visible_pixels={"bus_1": 12}, failures=[ValidationFailure("car_2", "offroad")])
    assert request.command_targets == (("bus_1",),) and request.visible_pixels == {"bus_1": 12}
    assert '"op": "remove"' in request.command_json and isinstance(request.failures, tuple)
    assert request.trajectory("bus_1") is None and request.log_trajectory("bus_1") is None
    with pytest.raises(ValueError, match="one entry per command"):
        JudgeRequest("p", [RGB], RGB, program=program, command_targets=[("a",), ("b",)])
    with pytest.raises(ValueError, match="kind must be one of"):
        ValidationFailure("car_2", "late")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"heading of car-1 must be \[3\]"):
        AgentTrajectory("car-1", "vehicle", "log", np.zeros((3, 2)), heading=np.zeros(4))
    xy = np.array([[0.0, 0.0], [np.nan, np.nan], [1.0, 0.0]])
    assert AgentTrajectory("car-1", "vehicle", "log", xy).present.tolist() == [True, False, True]
