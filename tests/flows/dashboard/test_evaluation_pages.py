"""The evaluation pages without a browser: every declared table of every run from its declaration, headline trends
across runs, the paper's figures beside ours, one table with its columns' meanings and units, and a corrupt table
shown as a message naming its file while the rest renders."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from fastapi.testclient import TestClient

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from simsplat_core.eval.editing.outcomes import EDITING_SPEC
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from simsplat_core.eval.table_registry import EVAL_TABLES
from storage import ArtifactStore
from storage.runs import run_dir, run_table, run_table_relpath, write_run_tables
from tests.flows.dashboard.evaluation_fixture import EVAL_RUNS, SEARCH_ROWS, editing_rows
from tests.flows.dashboard.store_fixture import DashboardStore


@pytest.fixture(scope="module")
def client(dashboard_store: DashboardStore) -> TestClient:
    return TestClient(create_app(DashboardSettings(dashboard_store.root)))


def _trend(body: dict, table: str, column: str) -> dict:
    return next(t for t in body["trends"]["value"] if t["table"] == table and t["column"] == column)


def test_every_run_lists_its_declared_tables_newest_first(client: TestClient) -> None:
    body = client.get("/api/evaluation").json()
    runs = body["runs"]["value"]
    assert [r["run_id"] for r in runs] == [run_id for run_id, _ in reversed(EVAL_RUNS)]
    newest = {s["value"]["name"]: s["value"] for s in runs[0]["tables"]}
    assert set(newest) == {"editing", "search"}
    editing = newest["editing"]
    assert [c["name"] for c in editing["columns"]] == list(EDITING_SPEC.column_names)
    assert editing["columns"][0]["key"] and editing["columns"][-1]["unit"] == "share"
    assert editing["num_rows"] == len(editing_rows(0.5))
    page = client.get("/evaluation")
    assert page.status_code == 200
    assert EDITING_SPEC.title in page.text and SEARCH_SPEC.title in page.text


def test_the_headline_trends_follow_the_declarations(client: TestClient) -> None:
    body = client.get("/api/evaluation").json()
    rate = _trend(body, "editing", "rate")
    assert rate["runs"] == [run_id for run_id, _ in EVAL_RUNS]
    ours = next(s for s in rate["series"] if s["label"] == "ours")
    assert ours["values"] == pytest.approx([r for _, r in EVAL_RUNS])
    assert rate["rows"] == "category = total"
    search = _trend(body, "search", "timestamp_ba")
    assert search["runs"] == [EVAL_RUNS[-1][0]]
    assert search["series"] == [{"label": "mean", "values": [pytest.approx(SEARCH_ROWS[0]["timestamp_ba"])]}]
    html = client.get("/evaluation").text
    assert html.count('<figure class="trend"') == len(body["trends"]["value"])
    assert html.count("<circle") >= len(EVAL_RUNS)


def test_the_papers_figures_sit_beside_ours(client: TestClient) -> None:
    paper = client.get("/api/evaluation").json()["paper"]
    editing = next(r for r in paper["rows"] if r["table"] == "editing")
    assert editing["paper"] == EDITING_SPEC.paper[0].value
    assert editing["ours"] == pytest.approx(EVAL_RUNS[-1][1]) and editing["ours_run"] == EVAL_RUNS[-1][0]
    motion = [r for r in paper["rows"] if r["table"] == "motion"]
    assert motion and all(r["ours"] is None for r in motion)  # declared, but no run of this store has the table
    without = set(paper["without_paper"])
    assert "search" in without and "editing" not in without
    assert without == {s.name for s in EVAL_TABLES.values() if not s.paper and not s.detail}
    html = client.get("/evaluation").text
    assert "The paper reports no figures for these tables" in html and "<code>search</code>" in html


def test_one_table_shows_every_column_with_its_meaning_and_unit(client: TestClient) -> None:
    run_id = EVAL_RUNS[-1][0]
    body = client.get(f"/api/evaluation/{run_id}/editing").json()
    table = body["table"]["value"]
    assert table["num_rows"] == table["shown_rows"] == 4
    assert [c["meaning"] for c in table["columns"]] == [c.meaning for c in EDITING_SPEC.columns]
    total = next(row for row in table["rows"] if row[0]["text"] == "ours" and row[1]["text"] == "total")
    assert total[-1]["paper"] == "0.842"  # the paper's figure on the cell it reports
    assert ("rate", "ours", pytest.approx(EVAL_RUNS[-1][1])) in [tuple(h) for h in body["headlines"]]
    page = client.get(f"/evaluation/{run_id}/editing")
    assert page.status_code == 200 and "completed / prompts" in page.text and "paper 0.842" in page.text


@pytest.mark.parametrize("path", ["/evaluation/no-such-run/editing", f"/evaluation/{EVAL_RUNS[0][0]}/search",
                                  f"/evaluation/{EVAL_RUNS[0][0]}/not-declared", "/evaluation/..%2F..%2Fetc/editing"])
def test_an_unknown_run_or_table_is_a_404(client: TestClient, path: str) -> None:
    assert client.get(path).status_code == 404
    assert client.get("/api" + path).status_code == 404


def _corrupt_store(root: Path) -> ArtifactStore:
    """Two runs: one with a truncated ``editing`` Parquet and a good ``search`` table, one whose ``editing`` has a
    column of the wrong type."""
    store = ArtifactStore(str(root))
    good = {EDITING_SPEC.name: run_table(EDITING_SPEC, EDITING_SPEC.table(editing_rows(0.5))),
            SEARCH_SPEC.name: run_table(SEARCH_SPEC, SEARCH_SPEC.table(SEARCH_ROWS))}
    write_run_tables(store, run_dir("eval-a"), good)
    truncated = root / run_table_relpath(run_dir("eval-a"), "editing")
    truncated.write_bytes(truncated.read_bytes()[:100])
    write_run_tables(store, run_dir("eval-b"), {EDITING_SPEC.name: good[EDITING_SPEC.name]})
    wrong = pa.table({**{n: EDITING_SPEC.table(editing_rows(0.5)).column(n) for n in EDITING_SPEC.column_names},
                      "rate": pa.array(["high"] * 4)})
    pq.write_table(wrong, root / run_table_relpath(run_dir("eval-b"), "editing"))
    return store


def test_a_corrupt_table_shows_a_message_naming_its_file_and_the_rest_renders(tmp_path: Path) -> None:
    _corrupt_store(tmp_path)
    client = TestClient(create_app(DashboardSettings(str(tmp_path))))
    body = client.get("/api/evaluation").json()
    sections = {(r["run_id"], s["name"]): s for r in body["runs"]["value"] for s in r["tables"]}
    truncated = sections[("eval-a", "table editing")]
    assert truncated["value"] is None and "eval-a/tables/editing.parquet" in truncated["error"]
    wrong = sections[("eval-b", "table editing")]
    assert "eval-b/tables/editing.parquet" in wrong["error"] and "rate" in wrong["error"]
    assert sections[("eval-a", "table search")]["value"]["num_rows"] == len(SEARCH_ROWS)
    assert [t["table"] for t in body["trends"]["value"]] == ["search", "search"]  # from the readable table only
    page = client.get("/evaluation")
    assert page.status_code == 200 and page.text.count('class="problem"') == 2 and SEARCH_SPEC.title in page.text
    one = client.get("/api/evaluation/eval-a/editing").json()
    assert "eval-a/tables/editing.parquet" in one["table"]["error"]
    assert client.get("/evaluation/eval-a/editing").status_code == 200


def test_a_store_without_runs_says_so(tmp_path: Path) -> None:
    client = TestClient(create_app(DashboardSettings(str(tmp_path / "empty"))))
    body = client.get("/api/evaluation").json()
    assert body["runs"]["value"] == [] and body["trends"]["value"] == []
    assert "No run in this store has evaluation tables" in client.get("/evaluation").text
    assert not (tmp_path / "empty").exists()
