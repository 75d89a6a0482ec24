"""``simsplat export``: a store's accepted scenarios as a dataset (formats, manifest, splits, increments, errors)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.export.from_log import log_agent_states
from simsplat_core.export.parquet_tables import read_dataset_table
from simsplat_core.scenario.agents import AgentStates
from storage import ArtifactStore
from storage.datasets import DatasetConflictError, list_datasets
from storage.edits import EditRecord, append_edit_records, staged_edit
from storage.inventory import MissingInputError
from storage.logs import write_scene_log
from tasks.export import ExportConfig, export_dataset, parse_splits, split_of
from tasks.export_inputs import ExportFilters
from tests.simsplat_core.export.log_fixtures import straight_road_log

SEQS = ("road-a", "road-b", "road-c")


def _edited(states: AgentStates, who: str = "car_a", *, crash: bool = False) -> AgentStates:
    """``states`` with ``who`` (the lead car) speeding up from 1 s (or, with ``crash``, driving into the ego)."""
    k = states.index(who)
    xy, speed = states.xy.copy(), states.speed.copy()
    if crash:
        xy[k] = states.xy[states.index("ego")]
    else:
        v = 6.0 + 1.5 * np.clip(states.times - 1.0, 0, None)
        xy[k, :, 0] = states.xy[k, 0, 0] + np.concatenate([[0.0], np.cumsum(v[:-1] * 0.1)])
        speed[k] = v
    sources = tuple("edited" if r == k else s for r, s in enumerate(states.sources))
    return dataclasses.replace(states, xy=xy, speed=speed, sources=sources)


def _add_edit(store: ArtifactStore, run: str, seq: str, edit_id: str, *, status: str = "accepted",
              category: str = "modify_vehicle", plausibility: int = 4, crash: bool = False) -> None:
    log = straight_road_log(seq_id=seq)
    mining = {"mining_status": status, "category": category, "plausibility": plausibility, "follows_prompt": True,
              "export": status == "accepted", "source": "seed", "client": "rule", "scenario": 0}
    record = EditRecord(run_id=run, seq_id=seq, edit_id=edit_id, prompt="the lead car speeds up",
                        command_json="{}", status="succeeded", mining=mining)
    with staged_edit(store, record, key=f"key-{edit_id}", append=False) as writer:
        writer.trajectories(edit_id, _edited(log_agent_states(log), crash=crash))
        writer.validation({"ok": not crash})
    append_edit_records(store, [record])


@pytest.fixture
def store(tmp_path: Path) -> ArtifactStore:
    store = ArtifactStore(str(tmp_path / "store"))
    for seq in SEQS:
        write_scene_log(store, straight_road_log(seq_id=seq))
    _add_edit(store, "mine-1", "road-a", "e0a")
    _add_edit(store, "mine-1", "road-b", "e0b", category="add_vehicle")
    _add_edit(store, "mine-1", "road-b", "e0c", status="rejected", plausibility=2)
    return store


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_accepted_scenarios_go_out_in_every_format_with_a_manifest(store: ArtifactStore, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = export_dataset(store.root, str(out), ExportConfig(name="ds"))
    root = out / "ds"
    assert result.written == 2 and result.increment == 1 and not result.left_out
    manifest = json.loads((root / "manifest.json").read_text())
    assert manifest["counts"]["scenarios"] == 2 and manifest["counts"]["by_category"] == {
        "add_vehicle": 1, "modify_vehicle": 1}
    assert set(manifest["inputs"]) == {"mine-1/road-a/e0a/1", "mine-1/road-b/e0b/1"}
    assert manifest["inputs"]["mine-1/road-a/e0a/1"] == "key-e0a"
    for shard in manifest["increments"][0]["shards"]:  # every shard's checksum is the file's
        assert _sha(root / shard["path"]) == shard["sha256"]
    assert {s["format"] for s in manifest["increments"][0]["shards"]} == {"womd", "scenarionet", "parquet"}
    assert "Licences" in (root / "DATACARD.md").read_text() and "simsplat's procedural world" in \
        (root / "DATACARD.md").read_text()
    for sid, entry in manifest["scenarios"].items():
        assert entry["split"] == split_of(entry["seq_id"], (("train", 0.8), ("val", 0.2)))
        assert entry["track_ids"]["ego"] == 0 and sid.endswith("-w0")
    agents = read_dataset_table(str(root / "parquet"), "agents", split=None)
    assert set(agents.column("scenario_id").to_pylist()) == set(manifest["scenarios"])
    (listing,) = list_datasets(store)
    assert listing["name"] == "ds" and listing["counts"]["scenarios"] == 2


def test_a_grown_store_adds_shards_and_rewrites_none(store: ArtifactStore, tmp_path: Path) -> None:
    out = tmp_path / "out"
    config = ExportConfig(name="ds", formats=("womd", "parquet"))
    first = export_dataset(store.root, str(out), config)
    before = {s.path: _sha(out / "ds" / s.path) for s in first.shards}
    again = export_dataset(store.root, str(out), config)
    assert again.increment == 0 and again.written == 0 and again.skipped_existing == 2
    _add_edit(store, "mine-1", "road-c", "e0d")
    grown = export_dataset(store.root, str(out), config)
    assert grown.increment == 2 and grown.written == 1 and grown.skipped_existing == 2
    assert all(_sha(out / "ds" / path) == sha for path, sha in before.items())
    assert not {s.path for s in grown.shards} & set(before)
    manifest = json.loads((out / "ds" / "manifest.json").read_text())
    assert manifest["counts"]["scenarios"] == 3 and len(manifest["increments"]) == 2


def test_a_killed_export_leaves_the_dataset_as_it_was(store: ArtifactStore, tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    import tasks.export as export_task

    out = tmp_path / "out"
    config = ExportConfig(name="ds", formats=("womd", "parquet"))
    real = export_task.write_format

    def dies_on_parquet(folder, fmt, *args, **kwargs):  # type: ignore[no-untyped-def]
        if fmt == "parquet":
            raise KeyboardInterrupt
        return real(folder, fmt, *args, **kwargs)

    monkeypatch.setattr(export_task, "write_format", dies_on_parquet)
    with pytest.raises(KeyboardInterrupt):  # killed during the first export: the folder is claimed, holds nothing
        export_dataset(store.root, str(out), config)
    manifest = json.loads((out / "ds" / "manifest.json").read_text())
    assert manifest["increments"] == [] and manifest["scenarios"] == {}
    assert all(not p.name.startswith(".") for p in (out / "ds").rglob("*") if p.is_file())  # no half file
    monkeypatch.setattr(export_task, "write_format", real)
    assert export_dataset(store.root, str(out), config).written == 2
    before = (out / "ds" / "manifest.json").read_bytes()
    _add_edit(store, "mine-1", "road-c", "e0d")
    monkeypatch.setattr(export_task, "write_format", dies_on_parquet)
    with pytest.raises(KeyboardInterrupt):  # killed while adding: the dataset is still the first increment
        export_dataset(store.root, str(out), config)
    assert (out / "ds" / "manifest.json").read_bytes() == before
    monkeypatch.setattr(export_task, "write_format", real)
    result = export_dataset(store.root, str(out), config)
    assert result.increment == 2 and result.written == 1 and result.skipped_existing == 2


def test_filters_and_splits(store: ArtifactStore, tmp_path: Path) -> None:
    only = ExportConfig(name="veh", formats=("parquet",), filters=ExportFilters(categories=("add_vehicle",)))
    assert export_dataset(store.root, str(tmp_path / "o1"), only).written == 1
    every = ExportConfig(name="all", formats=("parquet",), filters=ExportFilters(include="all-edits"))
    assert export_dataset(store.root, str(tmp_path / "o2"), every).written == 3
    logs = ExportConfig(name="logs", formats=("parquet",), filters=ExportFilters(include="logs"))
    assert export_dataset(store.root, str(tmp_path / "o3"), logs).written == 3
    picky = ExportConfig(name="p", formats=("parquet",), filters=ExportFilters(include="all-edits",
                                                                                min_plausibility=3))
    assert export_dataset(store.root, str(tmp_path / "o4"), picky).written == 2
    assert parse_splits("train=0.7, val=0.2,test=0.1") == (("train", 0.7), ("val", 0.2), ("test", 0.1))
    names = [split_of(f"log-{k}", parse_splits("train=0.5,val=0.5")) for k in range(200)]
    assert 60 < names.count("train") < 140  # a hash, not the first split for everything
    for bad in ("train=0.8", "train=0.5,train=0.5", "train", "train=-1,val=2"):
        with pytest.raises(ValueError, match="--split"):
            parse_splits(bad)


def test_a_failing_scenario_is_reported_and_left_out_unless_kept(store: ArtifactStore, tmp_path: Path) -> None:
    _add_edit(store, "mine-2", "road-c", "crash", crash=True)
    filters = ExportFilters(runs=("mine-2",))
    result = export_dataset(store.root, str(tmp_path / "o"), ExportConfig(name="d", formats=("womd",),
                                                                         filters=filters))
    assert result.written == 0 and "collides" in next(iter(result.left_out.values()))
    kept = export_dataset(store.root, str(tmp_path / "o2"), ExportConfig(name="d", formats=("womd",),
                                                                         filters=filters, keep_failing=True))
    assert kept.written == 1


def test_bad_input_is_refused_and_nothing_is_overwritten(store: ArtifactStore, tmp_path: Path) -> None:
    with pytest.raises(MissingInputError, match="no driving log"):
        export_dataset(str(tmp_path / "empty"), str(tmp_path / "o"))
    with pytest.raises(MissingInputError, match="no such edit run"):
        export_dataset(store.root, str(tmp_path / "o"), ExportConfig(filters=ExportFilters(runs=("nope",))))
    with pytest.raises(ValueError, match="unknown"):
        ExportFilters(categories=("flying_cars",))
    _add_edit(store, "mine-3", "road-c", "rej", status="rejected")
    with pytest.raises(MissingInputError, match="no accepted scenario"):
        export_dataset(store.root, str(tmp_path / "o"), ExportConfig(filters=ExportFilters(runs=("mine-3",))))
    other = tmp_path / "o" / "ds"
    other.mkdir(parents=True)
    (other / "mine.txt").write_text("not yours")
    with pytest.raises(DatasetConflictError, match="already holds files"):
        export_dataset(store.root, str(tmp_path / "o"), ExportConfig(name="ds"))
    assert (other / "mine.txt").read_text() == "not yours" and len(list(other.iterdir())) == 1
    export_dataset(store.root, str(tmp_path / "o"), ExportConfig(name="ds2", formats=("womd",)))
    with pytest.raises(DatasetConflictError, match="holds another dataset"):
        export_dataset(store.root, str(tmp_path / "o"), ExportConfig(name="ds2", formats=("parquet",)))


def test_scenarionet_index_lists_every_part(store: ArtifactStore, tmp_path: Path) -> None:
    out = tmp_path / "out"
    config = ExportConfig(name="sn", formats=("scenarionet",), splits=(("train", 1.0),))
    export_dataset(store.root, str(out), config)
    _add_edit(store, "mine-1", "road-c", "e0d")
    export_dataset(store.root, str(out), config)
    base = out / "sn" / "scenarionet" / "train"
    mapping = pickle.loads((base / "dataset_mapping.pkl").read_bytes())
    summary = pickle.loads((base / "dataset_summary.pkl").read_bytes())
    assert len(mapping) == len(summary) == 3
    assert all((base / part / name).is_file() for name, part in mapping.items())


def test_the_cli_exports_and_names_bad_options(store: ArtifactStore, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from flows.cli import app

    out = str(tmp_path / "cli")
    result = CliRunner().invoke(app, ["export", "--store", store.root, "--out", out, "--name", "ds",
                                      "--format", "womd,parquet", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output.strip().splitlines()[-1])
    assert sum(len(v) for v in data["new_scenarios"].values()) == 2 and data["increment"] == 1
    shown = CliRunner().invoke(app, ["export", "--store", store.root, "--out", out, "--name", "ds",
                                     "--format", "womd,parquet"])
    assert shown.exit_code == 0 and "up to date" in shown.output and "2 already in the dataset" in shown.output
    bad = CliRunner().invoke(app, ["export", "--store", store.root, "--category", "flying_cars"])
    assert bad.exit_code == 2 and "flying_cars" in bad.output
    wrong = CliRunner().invoke(app, ["export", "--store", store.root, "--format", "csv"])
    assert wrong.exit_code == 2 and "csv" in wrong.output
