"""The main flow mines as a mining configuration says, logs without camera images included: a store holding only the
public Waymo Open Motion scenario (no images) is aligned and mined per the file (saved search, edit categories,
counts) on threads, on the graph of its tracks with no asset bank built, its accepted scenario appended to the file's
dataset like any other, and the run record names the file, its version and its content key. (Logs with images are
mined in ``test_pipeline.py``.) Skipped when ../shared/data is absent."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from flows.pipeline import main_flow, plans_from_config, reconstruction_config
from flows.runtime import RunnerKind, make_task_runner
from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import AlignmentConfig
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES
from simsplat_core.world import WorldConfig
from storage import ArtifactStore
from storage.assets import list_asset_banks
from storage.edits import read_edit_manifest, read_edit_records
from storage.run_records import read_run_record, read_stage_matrix
from tasks.logs import ingest_real_log
from tasks.mining_config import load_mining_config

pytestmark = [pytest.mark.orchestration, pytest.mark.shared_data]

SAMPLE = "waymo/motion_data_one_scenario.tfrecord"
WORLD = WorldConfig(num_frames=6, width=80, height=56, test_every=3)  # no synthetic log is generated
ALIGN = dict(alignment=AlignmentConfig(), aligner=MotionAlignerConfig(epochs=3))
#: Vehicle edits and removals (the Waymo scenario's agents are mostly vehicles), one accepted scenario per log.
CONFIG = {"version": 1,
          "searches": {"queries": ["a car following another car"], "variants_per_hit": 1},
          "mining": {"scenarios_per_log": 1, "categories": ["modify_vehicle", "remove"], "max_attempts": 2},
          "vlm": {"client": "rule"},
          "dataset": {"name": "nightly", "formats": ["parquet"]}}


def test_a_mining_config_mines_a_log_without_images_and_exports_it(prefect_api_url, shared_data: Path,
                                                                   tmp_path: Path) -> None:
    root, out = str(tmp_path / "store"), str(tmp_path / "datasets")
    motion = ingest_real_log.fn(root, "waymo-scenario", str(shared_data / SAMPLE)).summary.seq_id
    config_path = tmp_path / "mining.yaml"
    config_path.write_text(yaml.safe_dump(CONFIG))
    loaded = load_mining_config(config_path)
    mining, export = plans_from_config(loaded, export_out=out)
    flow = main_flow.with_options(task_runner=make_task_runner(RunnerKind.threads, 2))
    result = flow(store_root=root, seeds=[], config=WORLD, reconstruction=reconstruction_config(30), mining=mining,
                  export=export, run_id="nightly-1", **ALIGN)

    store = ArtifactStore(root)
    assert [(p.seq_id, p.reconstructs) for p in result.stages] == [(motion, False)]
    assert [m.seq_id for m in result.mining] == [motion] and not list_asset_banks(store)  # boxes: no bank needed
    rows = read_edit_records(store, "nightly-1")
    assert rows and {r.seq_id for r in rows} == {motion}
    for row in rows:  # every attempt is of a selected category, or refused for not being one
        assert row.mining["category"] in CONFIG["mining"]["categories"] or (
            row.mining["category"] in EDIT_CATEGORIES and row.failure_reason.startswith("category_not_selected"))
    by_seq = {m.seq_id: m for m in result.mining}
    assert by_seq[motion].accepted == 1  # mined on its tracks: box-only bank, judged on the BEV and trajectories
    (scenario,) = by_seq[motion].scenarios
    manifest = read_edit_manifest(store, "nightly-1", motion, scenario.edit_id)
    assert manifest is not None and manifest["scene_hash"] == ""
    assert not store.exists(f"edits/nightly-1/{motion}/{scenario.edit_id}/renders")

    # exported into the file's dataset like any other scenario
    assert result.export is not None and result.export.dataset_uri.rstrip("/").endswith("datasets/nightly")
    entries = json.loads((Path(out) / "nightly" / "manifest.json").read_text())["scenarios"]
    assert result.export.written == len(entries) == 1
    assert [e["seq_id"] for e in entries.values()] == [motion]

    record = read_run_record(store, "nightly-1")
    assert record.parameters["mining"]["config"] == {"path": str(config_path), "version": 1, "key": loaded.key}
    matrix = read_stage_matrix(store, "nightly-1")
    assert matrix.cell(motion, "mine").status == "completed" and matrix.cell(motion, "reconstruct").status == "skipped"
    assert record.counts["accepted_scenarios"] == sum(m.accepted for m in result.mining)
