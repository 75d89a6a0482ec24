"""``evaluate_all``: the evaluations a store's contents allow (the rest skipped with a reason), the tables, the
summary and the manifest."""

from __future__ import annotations

import pytest

from simsplat_core.eval.plan import EVAL_GROUPS, StoreContents, plan_evaluation
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from simsplat_core.world.config import WorldConfig
from simsplat_core.world.generate import generate_log
from storage import ArtifactStore, write_scene_log
from storage.runs import read_run_table
from tasks.eval_all import EvalAllConfig, evaluate_all


def test_the_plan_follows_what_the_store_holds() -> None:
    contents = StoreContents(logs=("a", "b", "r"), synthetic=("a", "b"), ground_truth=("a",), scenes=("a",),
                             aligned=("a", "r"))
    steps = {s.group: s for s in plan_evaluation(contents)}
    assert list(steps) == list(EVAL_GROUPS)
    assert steps["reconstruction"].runs and steps["reconstruction"].seq_ids == ("a",)
    assert steps["throughput"].runs and steps["grounding"].seq_ids == ("a",)
    assert steps["editing"].skip.startswith("no asset bank") and steps["motion"].skip.startswith("no asset bank")
    assert steps["mining"].skip.startswith("no asset bank") and steps["search"].seq_ids == ("a", "b")
    bare = {s.group: s.skip for s in plan_evaluation(StoreContents(logs=("r",)), ("grounding", "search"))}
    assert bare == {"grounding": "no aligned synthetic log with ground-truth images",
                    "search": "no synthetic log (the search's ground truth)"}
    with pytest.raises(KeyError, match="unknown evaluation"):
        plan_evaluation(contents, ("nope",))


@pytest.fixture(scope="module")
def logs_only(tmp_path_factory: pytest.TempPathFactory) -> str:
    root = tmp_path_factory.mktemp("eval_all_store")
    for seed in (61, 62):
        write_scene_log(ArtifactStore(str(root)), generate_log(seed=seed, config=WorldConfig(num_frames=30,
                                                                                               render_images=False)))
    return str(root)


def test_a_store_of_image_less_logs_gets_the_search_table_and_reasons_for_the_rest(logs_only: str, tmp_path) -> None:
    result = evaluate_all(logs_only, out_root=str(tmp_path), run_id="eval-test", config=EvalAllConfig())
    assert list(result.tables) == ["search"]
    assert result.skipped == {
        "reconstruction": "no reconstructed scene",
        "throughput": "no recorded stage timings (no reconstructed scene, aligner or mined run)",
        "grounding": "no aligned synthetic log with ground-truth images",
        "editing": "no aligned synthetic log with ground-truth images",
        "motion": "no aligned synthetic log with ground-truth images",
        "mining": "no aligned log",
    }
    out = ArtifactStore(str(tmp_path))
    table = read_run_table(out, "", SEARCH_SPEC)
    assert table.num_rows > 0
    assert (tmp_path / "tables" / "search.md").read_text().startswith("# Search: RefAV balanced accuracies")
    manifest = out.read_json("manifest.json")
    assert manifest["run_id"] == "eval-test" and manifest["tables"] == ["search"] and manifest["code_version"]
    assert sorted(manifest["content_keys"]["logs"]) == ["synth-000061", "synth-000062"]
    assert manifest["config"]["per_category"] == 30 and manifest["skipped"] == result.skipped
    assert set(manifest["seconds"]) == {"search"} and manifest["table_seconds"]["search"] >= 0
    summary = (tmp_path / "summary.md").read_text()
    assert "| search | " in summary and "- grounding: no aligned synthetic log" in summary


def test_inside_the_store_the_run_lands_under_runs(logs_only: str) -> None:
    result = evaluate_all(logs_only, run_id="eval-inside", config=EvalAllConfig(groups=("reconstruction",)))
    assert result.tables == {} and result.skipped == {"reconstruction": "no reconstructed scene"}
    assert result.run_dir.endswith("runs/eval-inside") and result.out_relpath == "runs/eval-inside"
    assert ArtifactStore(logs_only).read_json("runs/eval-inside/manifest.json")["tables"] == []


def test_a_store_without_logs_is_an_error(tmp_path) -> None:
    with pytest.raises(ValueError, match="no driving log"):
        evaluate_all(str(tmp_path))


def test_load_run_tables_reads_the_declared_tables_back(logs_only: str, tmp_path) -> None:
    from tasks.run_tables import load_run_tables

    evaluate_all(logs_only, out_root=str(tmp_path), config=EvalAllConfig(groups=("search",)))
    (spec, table), = load_run_tables(str(tmp_path))
    assert spec is SEARCH_SPEC and table.num_rows > 0
    header, rows = spec.rows_for_console(table)
    assert header[0] == "query" and len(rows) == table.num_rows
