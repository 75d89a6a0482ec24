"""``tasks.mining_eval.evaluate_mining_run`` on the small store of ``test_edit`` (the mining tables, the openai row
when no endpoint is configured, the re-check read from the stored trajectories, the stored scenes untouched), and
the mining task against a faulty VLM endpoint (down, slow, schema-violating commands, a malformed verdict): every
attempt failed with its reason, bounded retries, the run goes on, nothing accepted."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest

from simsplat_core.eval.mining import MINING_BY_CATEGORY_SPEC, MINING_SPEC, MINING_STAGES_SPEC
from simsplat_core.eval.search.evaluate import SEARCH_SPEC
from simsplat_core.eval.search.queries import ALL_QUERIES
from simsplat_core.mining.openai_vlm import OpenAIVLMClient
from simsplat_core.mining.vlm_prompts import COMMAND_TOOL, JUDGE_TOOL, PROPOSE_TOOL
from simsplat_core.scenario.agents import EGO_ID
from storage import ArtifactStore
from storage.edits import read_edit_records
from tasks.mine import mine_sequence_task
from tasks.mining_eval import evaluate_mining_run
from tasks.search_eval import search_run_table
from tests.simsplat_core.vlm.chat_server import ChatServer, chat_client, slow, tool_reply
from tests.tasks.test_edit import store_root, world  # noqa: F401  (fixtures: the small store)
from tests.tasks.test_mine import SEQ, _relaxed_client

REMOVE = "Remove the white sedan."
PROPOSED = "Delete the white sedan from the scene."


def _stored_paths(root: str) -> set[str]:
    """Every path of the store ``root`` but the edits, the commit locks (``.locks/``: lock files, not
    artifacts) and the derived caches (``cache/``: search facts and grounding answers, which any reader may
    fill and which are recomputed when missing)."""
    return {str(p.relative_to(root)) for p in Path(root).rglob("*")
            if not {"edits", ".locks", "cache"} & set(p.relative_to(root).parts)}


@pytest.fixture(scope="module")
def evaluated(store_root: str, tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path, set[str]]:  # noqa: F811
    before = _stored_paths(store_root)
    out = tmp_path_factory.mktemp("mining_eval")
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("SIMSPLAT_VLM_URL", raising=False)
        mp.delenv("SIMSPLAT_VLM_MODEL", raising=False)
        result = evaluate_mining_run.fn(store_root, [SEQ], str(out), clients=("rule", "openai"), per_sequence=1,
                                        max_attempts=2, client_overrides={"rule": _relaxed_client()}, cores=2,
                                        search_table=search_run_table)
    return result, out, before


def test_the_mining_tables_are_written_with_a_row_per_client(store_root: str, evaluated) -> None:  # noqa: F811
    result, out, before = evaluated
    store = ArtifactStore(str(out))
    mining = store.read_table("tables/mining.parquet", MINING_SPEC.schema).to_pylist()
    assert [r["client"] for r in mining] == ["rule", "openai"]
    rule, openai = mining
    assert rule["ran"] and rule["accepted"] == 1 and rule["prompts"] >= 1
    assert rule["completion"] == pytest.approx(1 / rule["prompts"]) and 1.0 <= rule["attempts_mean"] <= 2.0
    assert rule["accepted_with_failure"] == 0 and result.failed_scenarios == []
    assert not openai["ran"] and openai["prompts"] == 0 and "SIMSPLAT_VLM_URL" in openai["note"]
    rows = read_edit_records(ArtifactStore(store_root), result.runs["rule"])
    assert rule["prompts"] == len({r.mining["scenario"] for r in rows})  # a proposal is a scenario of the run
    by_category = store.read_table("tables/mining_by_category.parquet",
                                   MINING_BY_CATEGORY_SPEC.schema).to_pylist()
    total = [r for r in by_category if r["category"] == "total"]
    assert [(r["client"], r["prompts"], r["accepted"]) for r in total] == [("rule", rule["prompts"], 1)]
    stages = store.read_table("tables/mining_stages.parquet", MINING_STAGES_SPEC.schema).to_pylist()
    (row,) = [r for r in stages if r["stage"] == "total"]
    assert row["accepted_per_hour_per_core"] == pytest.approx(1 / (row["seconds"] / 3600 * 2))
    assert {r["stage"] for r in stages if r["seconds"] > 0} >= {"load", "apply", "validate", "judge"}
    for name in ("mining", "mining_by_category", "mining_stages"):
        assert (out / "tables" / f"{name}.md").read_text().startswith("| ")
    search = store.read_table("tables/search.parquet", SEARCH_SPEC.schema).to_pylist()  # the search benchmark
    assert len(search) == len(ALL_QUERIES) and all(0.0 <= (r["log_ba"] or 0.0) <= 1.0 for r in search)
    assert (out / "tables" / "search.md").read_text().startswith("# Search")
    after = _stored_paths(store_root)
    assert after == before  # the stored scenes, logs and banks are not written


def test_the_recheck_reads_the_stored_trajectories_not_the_loops_flag(store_root: str, evaluated,  # noqa: F811
                                                                      monkeypatch: pytest.MonkeyPatch,
                                                                      tmp_path: Path) -> None:
    from storage.edits import read_trajectories

    def crashed(store, run_id, seq_id, edit_id) -> pa.Table:  # every agent driven onto the ego
        table = read_trajectories(store, run_id, seq_id, edit_id)
        oid, step = table.column("object_id").to_pylist(), table.column("step").to_numpy()
        ego = {s: (x, y) for o, s, x, y in zip(oid, step, table.column("x").to_numpy(), table.column("y").to_numpy())
               if o == EGO_ID}
        x = np.array([ego.get(s, (xx, 0))[0] + (0.0 if o == EGO_ID else 0.3)
                      for o, s, xx in zip(oid, step, table.column("x").to_numpy())], np.float32)
        y = np.array([ego[s][1] if s in ego else yy for s, yy in zip(step, table.column("y").to_numpy())], np.float32)
        table = table.set_column(table.schema.get_field_index("x"), table.schema.field("x"), pa.array(x))
        return table.set_column(table.schema.get_field_index("y"), table.schema.field("y"), pa.array(y))

    monkeypatch.setattr("tasks.mining_eval.read_trajectories", crashed)
    monkeypatch.delenv("SIMSPLAT_VLM_URL", raising=False)
    result = evaluate_mining_run.fn(store_root, [SEQ], str(tmp_path), clients=("rule",), per_sequence=1,
                                    max_attempts=2, client_overrides={"rule": _relaxed_client()})
    (rule,) = result.mining
    assert rule["accepted"] == 1 and rule["accepted_with_failure"] == 1 and len(result.failed_scenarios) == 1


# ---------------------------------------------------------------------------------------------- faults
@pytest.fixture()
def server() -> Iterator[ChatServer]:
    srv = ChatServer().start()
    yield srv
    srv.stop()


def _proposing(prompt: str, *, command: dict[str, Any] | None = None, verdict: Any = None):
    """Answers by the tool asked for: proposes ``prompt``; the command and the verdict as given."""
    def reply(body: dict[str, Any]) -> tuple[Any, ...]:
        tool = body["tool_choice"]["function"]["name"]
        if tool == PROPOSE_TOOL:
            return tool_reply(PROPOSE_TOOL, {"prompts": [prompt]})(body)
        if tool == COMMAND_TOOL:
            return tool_reply(COMMAND_TOOL, command)(body)
        assert tool == JUDGE_TOOL
        return tool_reply(JUDGE_TOOL, verdict)(body)

    return reply


GOOD_REMOVE = {"commands": [{"op": "remove", "target": {"description": "the white sedan"}}]}
FAULTS = {
    "down": (None, "vlm_error: "),
    "slow": (slow(2.0, _proposing(PROPOSED, command=GOOD_REMOVE)), "timed out"),
    "schema-violating command": (_proposing(PROPOSED, command={"commands": [{"op": "explode"}]}), COMMAND_TOOL),
    "malformed verdict": (_proposing(PROPOSED, command=GOOD_REMOVE, verdict='{"follows_prompt": "yes", plaus'),
                          JUDGE_TOOL),
}


@pytest.mark.parametrize("fault", list(FAULTS))
def test_a_faulty_endpoint_fails_attempts_with_reasons_and_the_run_goes_on(
        store_root: str, server: ChatServer, fault: str) -> None:  # noqa: F811
    reply, reason = FAULTS[fault]
    if reply is None:
        server.stop()  # nothing listens there any more
    else:
        server.reply = reply
    client = OpenAIVLMClient(chat_client(server, timeout_s=0.3, max_retries=1))
    run_id = f"faults-{fault.replace(' ', '-')}"
    summary = mine_sequence_task.fn(store_root, SEQ, run_id, per_sequence=1, max_attempts=2, seed=0,
                                    seed_prompts=(REMOVE,), client=client)
    assert summary.accepted == 0 and summary.scenarios == ()
    rows = read_edit_records(ArtifactStore(store_root), run_id)
    assert len(rows) == summary.attempts >= 2  # the seeded proposal, then the next one: the run went on
    assert all(r.status == "failed" and not r.export and r.failure_reason.startswith("vlm_error: ") for r in rows)
    assert any(reason in r.failure_reason for r in rows)
    if reply is not None:  # bounded: at most max_retries + 1 requests per call, a few calls per proposal
        assert len(server.requests) <= 2 * 3 * len(rows)
