"""The store the dashboard tests read: one small synthetic log with camera images (6 frames, 3 cameras, 64 x 48),
its initial scene graph, a ground-truth language scene, a two-asset bank, a mining run of the rule-based client
(accepted scenarios stored as edits, every attempt a row) and an exported dataset of that run; run records
(``run_records_fixture``)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from simsplat_core.language.text import default_text_encoder
from simsplat_core.mining.rule_client import RuleBasedVLMClient
from simsplat_core.mining.rule_judge import JudgeConfig
from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore
from tasks.export import ExportConfig, export_dataset
from tasks.export_inputs import ExportFilters
from tasks.mine import MiningSummary, mine_sequence_task
from tests.flows.dashboard.evaluation_fixture import add_evaluation_runs
from tests.flows.dashboard.run_records_fixture import add_run_records
from tests.small_store import write_small_store

SEQ = "synth-000000"
MINING_RUN = "mine-dash"
DATASET = "dash-set"
SCENE_HASH = "5ce9e" + "0" * 59
MODEL_HASH = "0de1" + "0" * 60
LANGUAGE_HASH = "1a9" + "0" * 61
FRAMES = 6

#: The rule-based judge without its render checks: the test scene's Gaussians are untrained, its renders blank.
RELAXED = JudgeConfig(blank_std=-1.0, hole_share=1.01, min_visible_pixels=0)


@dataclasses.dataclass(frozen=True)
class DashboardStore:
    """The built store: its root, the mining summary and the exported dataset's name."""

    root: str
    mining: MiningSummary
    dataset: str = DATASET
    seq_id: str = SEQ
    mining_run: str = MINING_RUN


def build_dashboard_store(root: Path) -> DashboardStore:
    """Build the store under ``root`` (module docstring); about half a minute on 2 cores."""
    store = ArtifactStore(str(root))
    log = generate_log(0, WorldConfig(num_frames=FRAMES, width=64, height=48))
    write_small_store(str(root), log, scene_hash=SCENE_HASH, model_hash=MODEL_HASH, language_hash=LANGUAGE_HASH)
    client = RuleBasedVLMClient(0, encoder=default_text_encoder(), judge_config=RELAXED)
    mining = mine_sequence_task.fn(str(root), SEQ, MINING_RUN, per_sequence=2, max_attempts=2, seed=0, client=client)
    export_dataset(str(root), None, dataclasses.replace(
        ExportConfig(), name=DATASET, filters=ExportFilters(include="accepted", runs=(MINING_RUN,))))
    add_run_records(str(root), mining, SEQ)
    add_evaluation_runs(store)
    return DashboardStore(str(root), mining)
