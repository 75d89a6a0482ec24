"""``simsplat mine`` on the small store of ``tests/tasks/test_edit`` (no Prefect server: the CLI calls the task's
function): ``--json`` summarises every sequence and matches the run's edits table (an OpenAI-compatible server
answering garbage: every attempt failed); missing inputs name the store and what to run. One test runs the task in
a Prefect flow (the session's server) for its artifacts."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flows.cli import app
from storage import ArtifactStore
from storage.edits import read_edit_records
from tasks.mine import MiningSummary, mine_sequence_task
from tests.simsplat_core.vlm.chat_server import ChatServer
from tests.tasks.test_edit import store_root, world  # noqa: F401  (fixtures: the small store)
from tests.tasks.test_mine import _relaxed_client, garbage_server  # noqa: F401  (fixture)

runner = CliRunner()


def test_mine_json_summarises_the_run(store_root: str, garbage_server: ChatServer) -> None:  # noqa: F811
    # the OpenAI client against a local server answering garbage: quick (the rule-based path is tests/tasks')
    result = runner.invoke(app, ["mine", "--store", store_root, "--per-sequence", "1", "--max-attempts", "1",
                                 "--vlm", "openai", "--run-id", "cli-mine", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads([line for line in result.output.splitlines() if line.startswith("{")][-1])
    assert out["run_id"] == "cli-mine" and out["edits_table"].endswith("edits/cli-mine/edits.parts")
    (seq,) = out["sequences"]
    assert seq["seq_id"] == "synth-000000" and seq["client"] == "openai-vlm:test-vlm"
    rows = read_edit_records(ArtifactStore(store_root), "cli-mine")
    assert out["totals"] == {"sequences": 1, "attempts": len(rows), "accepted": 0, "per_category": {}}
    assert out["scenarios"] == [] and seq["statuses"] == {"failed": len(rows)} and len(rows) >= 1
    assert all(r.failure_reason.startswith("vlm_error: ") for r in rows) and seq["seconds"]["total"] > 0


def test_mine_names_what_is_missing(store_root: str, tmp_path: Path) -> None:  # noqa: F811
    no_bank = tmp_path / "no_bank"
    shutil.copytree(store_root, no_bank, ignore=shutil.ignore_patterns("assets", "edits"))
    result = runner.invoke(app, ["mine", "--store", str(no_bank), "--json"])
    assert result.exit_code == 2 and "simsplat assets build" in result.output and "no asset bank" in result.output
    result = runner.invoke(app, ["mine", "--store", store_root, "--seq", "nowhere", "--json"])
    assert result.exit_code == 2 and "nowhere" in result.output
    result = runner.invoke(app, ["mine", "--store", store_root, "--vlm", "gpt", "--json"])
    assert result.exit_code == 2 and "gpt" in result.output


@pytest.mark.orchestration
def test_in_a_flow_the_task_publishes_progress_and_the_accepted_scenarios(prefect_api_url: str,
                                                                          store_root: str) -> None:  # noqa: F811
    from prefect import flow
    from prefect.client.orchestration import get_client
    from prefect.client.schemas.filters import ArtifactFilter, ArtifactFilterFlowRunId, FlowRunFilter, TaskRunFilter
    from prefect.client.schemas.sorting import ArtifactSort

    @flow(name="mine-test")
    def mine_flow(root: str) -> MiningSummary:
        return mine_sequence_task(root, "synth-000000", "flow-mine", per_sequence=1, max_attempts=2, seed=0,
                                  client=_relaxed_client())  # accepts soon: the run stops there

    state = mine_flow(store_root, return_state=True)
    summary = state.result()
    assert summary.accepted == 1 and summary.attempts == len(read_edit_records(ArtifactStore(store_root), "flow-mine"))
    with get_client(sync_client=True) as client:
        artifacts = client.read_artifacts(  # every argument given: this server rejects nulls
            artifact_filter=ArtifactFilter(flow_run_id=ArtifactFilterFlowRunId(any_=[state.state_details.flow_run_id])),
            flow_run_filter=FlowRunFilter(), task_run_filter=TaskRunFilter(), sort=ArtifactSort.CREATED_DESC,
            limit=50, offset=0)
    kinds = {(a.type, a.key) for a in artifacts}
    assert ("progress", None) in kinds and ("table", "mining-synth-000000") in kinds


def test_mine_from_search_tries_variants_of_the_hits_first(store_root: str,  # noqa: F811
                                                           garbage_server: ChatServer) -> None:  # noqa: F811
    from tasks.search import search_seeds

    found, seeds = search_seeds(store_root, "a vehicle")
    assert found.hits and set(seeds) == {h.seq_id for h in found.hits}
    result = runner.invoke(app, ["mine", "--store", store_root, "--per-sequence", "1", "--max-attempts", "1",
                                 "--vlm", "openai", "--run-id", "from-search", "--from-search", "a vehicle", "--json"])
    assert result.exit_code == 0, result.output
    rows = read_edit_records(ArtifactStore(store_root), "from-search")
    first = seeds[rows[0].seq_id][0]
    assert rows[0].prompt == first.prompt and first.target_id in first.prompt
    assert rows[0].mining["source"] == "seed" and {r.seq_id for r in rows} <= set(seeds)
    result = runner.invoke(app, ["mine", "--store", store_root, "--from-search", "a purple bus reversing", "--json"])
    assert result.exit_code == 2 and "nothing to seed the loop with" in result.output
