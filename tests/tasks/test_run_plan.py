"""Planning a main run before anything starts: the first work found is named; an idle run is recorded with every
stage skipped and its reason, without Prefect."""

from __future__ import annotations

from pathlib import Path

import pytest

from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, write_scene_log
from storage.mining_ledger import LedgerRecord, LedgerScenario
from storage.run_records import read_run_record, read_stage_matrix
from tasks.align import StoredAligner, StoredLanguageScene
from tasks.landing import LandingPlan
from tasks.logs import stored_log
from tasks.mining_ledger import LedgerSplit
from tasks.reconstruct import StoredScene
from tasks.run_plan import RunAsked, RunPlan, plan_run, record_idle_run, skip_reasons
from tasks.stages import decide_stages
from tests.tasks.landing_files import make_landing

WORLD = WorldConfig(num_frames=2, width=32, height=24)


@pytest.fixture
def two_logs(tmp_path: Path) -> str:
    store = ArtifactStore(str(tmp_path / "store"))
    for seed in (0, 1):
        write_scene_log(store, generate_log(seed=seed, config=WORLD, seq_id=f"s{seed}"))
    return str(tmp_path / "store")


def test_the_first_work_found_is_named(two_logs: str, tmp_path: Path) -> None:
    assert plan_run(two_logs, RunAsked()).pending == ("reconstruct s0, s1",)
    assert plan_run(two_logs, RunAsked(seeds=(3,), world=WORLD)).pending == (
        "generate the synthetic sequence(s) of seed(s) [3]",)
    assert plan_run(str(tmp_path / "empty"), RunAsked()).pending == ("no log in the store yet",)


@pytest.mark.shared_data
def test_new_landing_logs_are_work(two_logs: str, shared_data: Path, tmp_path: Path) -> None:
    landing = make_landing(shared_data, tmp_path / "landing")
    plan = plan_run(two_logs, RunAsked(landing=str(landing)))
    assert plan.pending == ("3 new log(s) in the landing location",) and len(plan.landing.new) == 3


def _idle_plan(store_root: str) -> RunPlan:
    """``s0`` reconstructed, aligned and mined before; ``s1`` aligned, not minable (hand-built, as found)."""
    logs = (stored_log(store_root, "s0"), stored_log(store_root, "s1"))
    stages = (decide_stages("s0", "synthetic", 4), decide_stages("s1", "av2", 0))
    language = (StoredLanguageScene("s0", "scene0", "model", "lang0", "", {}, 0.0, True),
                StoredLanguageScene("s1", "", "model", "lang1", "", {}, 0.0, True))
    mined = LedgerRecord("key", "s0", "log0", "scene0", "lang0", "main-7", "2026-11-28T00:00:00+00:00", 2,
                         (LedgerScenario("e1", "the car stops", "modify_vehicle"),))
    return RunPlan((), LandingPlan((), (), ()), logs, stages, (StoredScene("s0", "scene0", "", {}, 0.0, True),),
                   StoredAligner("model", "", ("s0", "s1"), {}, 0.0, True), language, ("s0",),
                   LedgerSplit((), (mined,)))


def test_an_idle_run_skips_every_stage_with_its_reason(two_logs: str) -> None:
    reasons = skip_reasons(_idle_plan(two_logs), evaluate=True, export=True)
    assert reasons["s0", "reconstruct"] == "scene scene0 stored" and reasons["s1", "reconstruct"] == "no camera images"
    assert reasons["s0", "mine"] == "mined by run main-7 with these settings (1 accepted: e1)"
    assert reasons["s0", "export"] == "no new scenario (mined by run main-7)"
    assert reasons["s1", "mine"] == reasons["s1", "export"] == "not among the sequences this run mines"
    assert reasons["s1", "evaluate"] == "no camera images"
    assert reasons["s0", "ingest"] == reasons["s1", "ingest"] == "in the store before this run"
    quiet = skip_reasons(_idle_plan(two_logs), evaluate=False, export=False)
    assert not {stage for _, stage in quiet} & {"evaluate", "export"}


def test_an_idle_run_is_recorded_without_prefect_and_a_busy_one_is_refused(two_logs: str) -> None:
    record_idle_run(two_logs, "main-idle", _idle_plan(two_logs), {"landing": "/landing"}, evaluate=False,
                    export=False)
    store = ArtifactStore(two_logs)
    record = read_run_record(store, "main-idle")
    assert (record.status, record.flow, record.parameters) == ("completed", "simsplat-main", {"landing": "/landing"})
    assert record.counts == {"logs": 2, "scenes": 1, "landed": 0, "quarantined": 0, "language_scenes": 2,
                             "accepted_scenarios": 0, "mined_before": 1}
    matrix = read_stage_matrix(store, "main-idle")
    assert matrix.cell("s0", "mine").status == "skipped" and matrix.cell("s1", "align").status == "skipped"
    with pytest.raises(ValueError, match="reconstruct s0"):
        record_idle_run(two_logs, "main-busy", RunPlan(("reconstruct s0",)), {}, evaluate=False, export=False)
    assert read_run_record(store, "main-busy") is None
