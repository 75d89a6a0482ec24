"""``tasks.mine.mine_sequence_task`` as a plain function (``.fn``) on the small store of ``test_edit`` (a 6-frame
log without pixels, its scene graph, a ground-truth language scene, a two-asset bank): one row per attempt with
its status and reason, accepted scenarios stored as edits, determinism per seed, and an OpenAI-compatible server
answering garbage (every attempt failed, nothing accepted, the run goes on), and one that is down (every attempt failed
naming the connection error, the sequence stopped early)."""

from __future__ import annotations

import socket
from collections.abc import Iterator
from pathlib import Path

import pytest

from simsplat_core.language.text import default_text_encoder
from simsplat_core.mining.loop import MAX_UNREACHABLE_IN_A_ROW
from simsplat_core.mining.rule_client import RuleBasedVLMClient
from simsplat_core.mining.rule_judge import JudgeConfig
from storage import ArtifactStore
from storage.edits import edit_dir, read_edit_manifest, read_edit_records, validation_from_json
from tasks.mine import MiningSummary, mine_sequence_task
from tests.simsplat_core.vlm.chat_server import ChatServer, text_reply
from tests.tasks.test_edit import store_root, world  # noqa: F401  (fixtures: the small store)

SEQ = "synth-000000"
EDIT_FILES = ("command.json", "trajectories.parquet", "delta/delta.json", "delta/pose_tracks.parquet", "bev.png",
              "before_after.png", "validation.json", "_SUCCESS.json")


#: The rule-based judge without its render checks: the test scene's Gaussians are untrained, its renders blank.
RELAXED = JudgeConfig(blank_std=-1.0, hole_share=1.01, min_visible_pixels=0)


def _mine(store_root: str, run_id: str, **kw) -> MiningSummary:  # noqa: F811
    kw.setdefault("per_sequence", 1)
    kw.setdefault("max_attempts", 2)
    kw.setdefault("seed", 0)
    return mine_sequence_task.fn(store_root, SEQ, run_id, vlm=kw.pop("vlm", "rule"), **kw)


def _relaxed_client() -> RuleBasedVLMClient:
    return RuleBasedVLMClient(0, encoder=default_text_encoder(), judge_config=RELAXED)


@pytest.fixture(scope="module")
def mined(store_root: str) -> MiningSummary:  # noqa: F811
    return _mine(store_root, "mine-a", client=_relaxed_client())


def test_every_attempt_is_a_row_and_accepted_scenarios_are_stored(store_root: str, mined: MiningSummary  # noqa: F811
                                                                  ) -> None:
    store = ArtifactStore(store_root)
    rows = read_edit_records(store, "mine-a")
    assert len(rows) == mined.attempts >= 1 and mined.accepted == 1
    assert sum(mined.statuses.values()) == mined.attempts and sum(mined.per_category.values()) == 1
    for row in rows:
        status = row.mining["mining_status"]
        assert status in ("accepted", "rejected", "refused", "failed") and row.mining["client"] == mined.client
        assert (status == "accepted") == (row.status == "succeeded") == row.export == (row.failure_reason == "")
        if status != "accepted":
            assert ": " in row.failure_reason  # "<reason>: <message>"
    (scenario,) = mined.scenarios
    (accepted,) = [r for r in rows if r.export]
    assert (accepted.edit_id, accepted.prompt) == (scenario.edit_id, scenario.prompt)
    rel = edit_dir("mine-a", SEQ, scenario.edit_id)
    files = set(store.walk(rel))
    assert set(EDIT_FILES) <= files and any(f.startswith("renders/") and f.endswith(".exr") for f in files)
    assert scenario.edit_dir == store.uri(rel) and read_edit_manifest(store, "mine-a", SEQ, scenario.edit_id)
    assert validation_from_json(store, "mine-a", SEQ, scenario.edit_id)["ok"] is True
    assert set(mined.seconds) >= {"load", "propose", "command", "edit", "render", "judge", "write", "total"}
    assert mined.edits_table.endswith("edits/mine-a/edits.parts")


def test_the_same_seed_mines_the_same_scenarios(store_root: str, mined: MiningSummary) -> None:  # noqa: F811
    again = _mine(store_root, "mine-b", client=_relaxed_client())
    store = ArtifactStore(store_root)

    def decided(run_id: str) -> list[tuple]:
        return [(r.edit_id, r.attempt, r.prompt, r.command_json, r.status, r.failure_reason, r.mining["mining_status"])
                for r in read_edit_records(store, run_id)]

    assert decided("mine-b") == decided("mine-a")
    assert [(s.edit_id, s.prompt, s.category) for s in again.scenarios] == \
        [(s.edit_id, s.prompt, s.category) for s in mined.scenarios]


@pytest.fixture()
def garbage_server(monkeypatch: pytest.MonkeyPatch) -> Iterator[ChatServer]:
    server = ChatServer().start()
    server.reply = text_reply("sure! here is a scenario: ~~~ not a function call ~~~")
    monkeypatch.setenv("SIMSPLAT_VLM_URL", server.base_url)
    monkeypatch.setenv("SIMSPLAT_VLM_MODEL", "test-vlm")
    monkeypatch.setenv("SIMSPLAT_VLM_API_KEY", "sk-test-secret")
    try:
        yield server
    finally:
        server.stop()


def test_a_vlm_answering_garbage_fails_its_attempts_and_the_run_goes_on(
        store_root: str, garbage_server: ChatServer, caplog: pytest.LogCaptureFixture) -> None:  # noqa: F811
    seed = "remove the white sedan"
    summary = _mine(store_root, "mine-vlm", vlm="openai", seed_prompts=(seed,))
    assert summary.accepted == 0 and summary.scenarios == () and summary.client == "openai-vlm:test-vlm"
    rows = read_edit_records(ArtifactStore(store_root), "mine-vlm")
    assert len(rows) == summary.attempts >= 2  # the seed prompt's command, then proposing
    assert rows[0].prompt == seed
    for row in rows:
        assert row.status == "failed" and row.mining["mining_status"] == "failed" and not row.export
        assert row.failure_reason.startswith("vlm_error: ")
    assert not (Path(store_root) / "edits" / "mine-vlm" / SEQ).exists() or not any(
        (p / "_SUCCESS.json").exists() for p in (Path(store_root) / "edits" / "mine-vlm" / SEQ).iterdir())
    assert garbage_server.requests and "sk-test-secret" not in caplog.text


def test_an_accepted_scenario_that_cannot_be_stored_is_recorded_as_failed(store_root: str,  # noqa: F811
                                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("tasks.mine.write_edit", broken)
    with pytest.raises(OSError, match="disk full"):
        _mine(store_root, "mine-broken", client=_relaxed_client())
    rows = read_edit_records(ArtifactStore(store_root), "mine-broken")
    assert rows and not any(r.export for r in rows)  # every attempt still has its row, nothing exported
    assert rows[-1].failure_reason == "error: OSError: disk full" and rows[-1].mining["mining_status"] == "failed"


@pytest.fixture()
def closed_port(monkeypatch: pytest.MonkeyPatch) -> int:
    """``SIMSPLAT_VLM_URL`` pointing at a port of 127.0.0.1 that nothing listens on."""
    with socket.socket() as probe:  # bound, then closed without listening: the port is free and refuses
        probe.bind(("127.0.0.1", 0))
        port = int(probe.getsockname()[1])
    monkeypatch.setenv("SIMSPLAT_VLM_URL", f"http://127.0.0.1:{port}/v1")
    monkeypatch.setenv("SIMSPLAT_VLM_MODEL", "test-vlm")
    return port


def test_a_vlm_down_for_the_whole_run_fails_every_attempt_and_stops_the_sequence_early(
        store_root: str, closed_port: int) -> None:  # noqa: F811
    seeds = tuple(f"remove the white sedan {n}" for n in range(MAX_UNREACHABLE_IN_A_ROW + 2))
    summary = _mine(store_root, "mine-down", vlm="openai", seed_prompts=seeds)
    assert summary.accepted == 0 and summary.scenarios == () and summary.statuses == {"failed": summary.attempts}
    rows = read_edit_records(ArtifactStore(store_root), "mine-down")
    assert len(rows) == summary.attempts == MAX_UNREACHABLE_IN_A_ROW < len(seeds)  # the rest is not attempted
    assert [r.prompt for r in rows] == list(seeds[:MAX_UNREACHABLE_IN_A_ROW])
    for row in rows:
        assert row.mining["mining_status"] == "failed" and not row.export
        assert row.failure_reason.startswith("vlm_error: command: VLMUnreachableError: ")
        assert f"127.0.0.1:{closed_port}" in row.failure_reason and "ConnectError" in row.failure_reason
    assert not (Path(store_root) / "edits" / "mine-down" / SEQ).exists()
