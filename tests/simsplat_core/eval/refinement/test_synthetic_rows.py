"""Rows of the synthetic (edit-based) motion benchmark from outcomes: the log row, one row per mode over the cases
every mode carried out, ``refused`` counted apart, ``predictor`` named for refined modes only, per-agent shares;
the outcomes table and its failures-only Markdown."""

from __future__ import annotations

import math

import pytest

from simsplat_core.eval.refinement.synthetic import MotionCase, MotionOutcome, outcome_row, synthetic_rows
from simsplat_core.eval.refinement.table import OUTCOME_COLUMNS, OUTCOMES_SPEC, motion_table, outcomes_table
from simsplat_core.scenario.rollout_metrics import ScenarioFailures

CRASH = ScenarioFailures(collision_vehicle=True, failed_agents=("car_2",))
CLEAN = ScenarioFailures()


def _outcome(case: str, mode: str, failures: ScenarioFailures | None = CLEAN, refused: str = "",
             **kw) -> MotionOutcome:
    return MotionOutcome(MotionCase(case, "seq0", "interaction", "sudden_stop", f"text {case}"), mode, refused=refused,
                         failures=None if refused else failures, progress=kw.pop("progress", 1.0),
                         stopped_share=kw.pop("stopped_share", 0.0), agents=10, collided=kw.pop("collided", 0),
                         offroad_agents=0, predictor="" if mode == "none" else "reactive", **kw)


def test_rows_per_mode_over_the_cases_every_mode_carried_out() -> None:
    outcomes = [_outcome("c1", "none", CRASH, collided=2), _outcome("c1", "single-agent"), _outcome("c1", "full"),
                _outcome("c2", "none"), _outcome("c2", "single-agent", progress=0.5), _outcome("c2", "full"),
                _outcome("c3", "none"), _outcome("c3", "single-agent", refused="no_asset: none"),
                _outcome("c3", "full")]
    logs = [_outcome("seq0:log", "log", stopped_share=0.25)]
    rows = synthetic_rows(outcomes, logs)
    assert [(r["method"], r["predictor"]) for r in rows] == [("log", ""), ("none", ""), ("single-agent", "reactive"),
                                                            ("full", "reactive")]
    log, none, single, full = rows
    assert log["scenarios"] == 1 and log["refused"] == 0 and log["stopped_share"] == 0.25
    assert none["scenarios"] == 2 and none["refused"] == 1  # c3 refused in one mode: left out of all
    assert none["collision_vehicle"] == 0.5 and none["agent_collision"] == pytest.approx(2 / 20)
    assert full["failure"] == 0.0 and single["progress"] == pytest.approx(0.75)
    assert none["ade_3s"] is None and {r["dataset"] for r in rows} == {"synthetic"}
    table = motion_table(rows)
    assert table.num_rows == 4


def test_outcomes_table_and_markdown_of_failures() -> None:
    outcomes = [_outcome("c1", "full", CRASH, details=("car_2 [refined vehicle]: collision with ego",)),
                _outcome("c2", "full"), _outcome("c3", "full", refused="no_asset: none")]
    table = outcomes_table([outcome_row(o) for o in outcomes])
    assert table.column_names == [n for n, _, _ in OUTCOME_COLUMNS] and table.num_rows == 3
    first = table.to_pylist()[0]
    assert first["failure"] and first["failed_agents"] == "car_2" and "collision with ego" in first["failure_details"]
    assert table.to_pylist()[2]["refused"] == "no_asset: none" and not table.to_pylist()[2]["failure"]
    assert math.isclose(first["progress"], 1.0)
    text = OUTCOMES_SPEC.render_markdown(table)
    assert "text c1" in text and "text c3" in text and "text c2" not in text  # failed and refused only
    with pytest.raises(KeyError, match="no column 'mode'"):
        outcomes_table([{k: v for k, v in outcome_row(outcomes[0]).items() if k != "mode"}])
