"""Edit fidelity metrics and the evaluation tables (schemas, rates, means)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simsplat_core.eval.editing.fidelity import FidelityScore, edit_fidelity, edit_region, render_fidelity
from simsplat_core.eval.editing.intents import EditIntent
from simsplat_core.eval.editing.observation import ViewSet
from simsplat_core.eval.editing.outcomes import (
    EDITING_SPECS,
    PromptOutcome,
    completion_table,
    failures_markdown,
    fidelity_table,
    infeasible_table,
    outcomes_table,
)
from simsplat_core.eval.editing.prompts import CATEGORIES, EditPrompt
from simsplat_core.eval.table_registry import table_spec
from storage.schemas.validation import validate_table


def _views(rgb: np.ndarray) -> ViewSet:
    return ViewSet((9, 19), ("a", "b"), rgb.astype(np.float32), np.zeros(rgb.shape[:4], np.int32))


def test_fidelity_of_a_perfect_and_a_noisy_edit() -> None:
    rng = np.random.default_rng(0)
    original = rng.uniform(0.2, 0.8, (2, 2, 16, 24, 3))
    edited_world = original.copy()
    edited_world[:, :, 4:10, 5:12] = 0.1  # the edit changes a patch
    region = edit_region(_views(edited_world), _views(original))
    assert region.sum() == 2 * 2 * 6 * 7
    perfect = edit_fidelity(_views(edited_world), _views(edited_world), _views(original), _views(original))
    assert math.isinf(perfect.psnr_region) and perfect.ssim == pytest.approx(1.0)
    assert math.isinf(perfect.psnr_unedited_region)
    noisy = edited_world + rng.normal(0, 0.05, edited_world.shape)
    score = edit_fidelity(_views(noisy), _views(edited_world), _views(original), None)
    assert 20 < score.psnr < 30 and 20 < score.psnr_region < 30 and math.isnan(score.psnr_unedited_region)
    missed = edit_fidelity(_views(original), _views(edited_world), _views(original), None)  # the edit not drawn
    assert missed.psnr_region < 12 < missed.psnr
    assert render_fidelity(_views(noisy), _views(edited_world))[0] == pytest.approx(score.psnr)
    with pytest.raises(ValueError, match="view sets differ"):
        render_fidelity(_views(noisy), ViewSet((9,), ("a", "b"), noisy[:1].astype(np.float32),
                                               np.zeros(noisy[:1].shape[:4], np.int32)))


def _prompt(category: str, n: int) -> EditPrompt:
    intent = EditIntent("remove", ("veh_00",)) if category != "infeasible" else EditIntent(
        "remove", expected_refusals=("not_found",), structured=False)
    return EditPrompt(f"s/{category}/{n}", "s", category, "k", 0, f"text {n}", intent, None)


def _outcomes() -> list[PromptOutcome]:
    out = []
    for method, done in (("ours", 2), ("chatsim-like", 1)):
        for category in CATEGORIES:
            for n in range(3):
                fid = FidelityScore(25.0 + n, 0.9, 20.0, 22.0, 12, 40) if n < done else None
                out.append(PromptOutcome(_prompt(category, n), method, n < done, "why", fidelity=fid))
        out.append(PromptOutcome(_prompt("infeasible", 0), method, True, "refused", refusal="not_found"))
        out.append(PromptOutcome(_prompt("infeasible", 1), method, method == "ours", "x",
                                 refusal="unsupported" if method == "ours" else ""))
    return out


def test_completion_and_infeasible_tables() -> None:
    table = completion_table(_outcomes())
    validate_table(table, table_spec("editing").schema, "editing", require_metadata=False)
    rows = {(r["method"], r["category"]): r for r in table.to_pylist()}
    assert len(rows) == 2 * 7
    assert rows[("ours", "remove")]["rate"] == pytest.approx(2 / 3)
    assert rows[("ours", "total")]["prompts"] == 18 and rows[("ours", "total")]["completed"] == 12
    assert rows[("chatsim-like", "total")]["rate"] == pytest.approx(1 / 3)
    inf = {r["method"]: r for r in infeasible_table(_outcomes()).to_pylist()}
    assert inf["ours"]["refused"] == 2 and inf["ours"]["expected_reason"] == 1
    assert inf["chatsim-like"]["rate"] == pytest.approx(0.5)


def test_fidelity_and_outcome_tables() -> None:
    table = fidelity_table(_outcomes(), {"s": 28.5})
    validate_table(table, table_spec("edit_fidelity").schema, "edit_fidelity", require_metadata=False)
    rows = {(r["method"], r["category"]): r for r in table.to_pylist()}
    assert rows[("ours", "add_vehicle")]["psnr"] == pytest.approx(25.5)
    assert rows[("ours", "total")]["edits"] == 12 and rows[("ours", "total")]["psnr_unedited"] == 28.5
    assert rows[("chatsim-like", "remove")]["psnr"] == pytest.approx(25.0)
    out = outcomes_table(_outcomes())
    validate_table(out, table_spec("editing_outcomes").schema, "editing_outcomes", require_metadata=False)
    assert out.num_rows == len(_outcomes())
    md = failures_markdown(_outcomes())
    assert md.count("\n") == 2 + 6 and "text 2" in md


def test_every_editing_table_has_a_schema() -> None:
    names = [spec.name for spec in EDITING_SPECS]
    assert names == ["editing", "editing_infeasible", "edit_fidelity", "editing_outcomes"]
    for name in names:
        schema = table_spec(name).schema
        assert schema.metadata[b"schema_name"] == name.encode()
    with pytest.raises(KeyError, match="no evaluation table"):
        table_spec("nope")
