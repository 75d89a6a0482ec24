"""The mining ledger's decisions: one key per set of mining settings, a sequence mined once per log and scene."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, write_scene_log
from tasks.align import StoredLanguageScene
from tasks.mining_ledger import MinedSequence, ledger_settings, mined_reason, record_mined, split_by_ledger


@dataclasses.dataclass(frozen=True)
class MiningPlan:
    """A run's mining settings (the flows' plan has these fields)."""

    per_sequence: int = 3
    max_attempts: int = 3
    vlm: str = "rule"
    seed: int = 0


def test_the_settings_key_changes_with_every_setting_that_decides_the_scenarios(monkeypatch) -> None:
    base = MiningPlan(per_sequence=2, max_attempts=3, vlm="rule", seed=0)
    key = ledger_settings(base).key
    assert ledger_settings(MiningPlan(per_sequence=2, max_attempts=3, vlm="rule", seed=0)).key == key
    changed = [dataclasses.replace(base, per_sequence=3), dataclasses.replace(base, max_attempts=1),
               dataclasses.replace(base, seed=1)]
    keys = {ledger_settings(plan).key for plan in changed} | {ledger_settings(base, config_key="cfg").key}
    monkeypatch.setenv("SIMSPLAT_VLM_URL", "http://127.0.0.1:9/v1")
    for model in ("model-a", "model-b"):
        monkeypatch.setenv("SIMSPLAT_VLM_MODEL", model)
        keys.add(ledger_settings(dataclasses.replace(base, vlm="openai")).key)
    assert len(keys) == 6 and key not in keys


def _language(seq_id: str, scene_hash: str) -> StoredLanguageScene:
    return StoredLanguageScene(seq_id, scene_hash, "model", f"language-{scene_hash}", "", {}, 0.0, True)


@pytest.fixture
def two_logs(tmp_path: Path) -> str:
    store = ArtifactStore(str(tmp_path))
    for seed in (0, 1):
        write_scene_log(store, generate_log(seed=seed, config=WorldConfig(num_frames=2, width=32, height=24),
                                            seq_id=f"s{seed}"))
    return str(tmp_path)


def test_a_sequence_is_mined_again_only_for_other_settings_another_log_or_another_scene(two_logs: str) -> None:
    store = ArtifactStore(two_logs)
    settings = ledger_settings(MiningPlan(per_sequence=1))
    candidates = [_language("s0", "scene-a"), _language("s1", "")]
    assert split_by_ledger(two_logs, candidates, settings.key).to_mine == ("s0", "s1")

    log_key = str(store.read_json("logs/s0/_SUCCESS.json")["key"])
    record = record_mined(store, settings, MinedSequence("s0", "run-1", log_key, "scene-a", "language-scene-a", 2,
                                                         (("e1", "the car stops", "modify_vehicle"),)))
    split = split_by_ledger(two_logs, candidates, settings.key)
    assert split.to_mine == ("s1",) and split.mined == (record,)
    assert record.settings["per_sequence"] == 1
    assert mined_reason(record) == "mined by run run-1 with these settings (1 accepted: e1)"
    # another scene of the log (reconstructed with other settings), other mining settings: mined again
    assert split_by_ledger(two_logs, [_language("s0", "scene-b")], settings.key).to_mine == ("s0",)
    other = ledger_settings(MiningPlan(per_sequence=1, seed=5))
    assert split_by_ledger(two_logs, candidates, other.key).to_mine == ("s0", "s1")
    # the log re-ingested with other content: its key changes, so it is mined again
    write_scene_log(store, generate_log(seed=7, config=WorldConfig(num_frames=2, width=32, height=24), seq_id="s0"))
    assert split_by_ledger(two_logs, candidates, settings.key).to_mine == ("s0", "s1")
