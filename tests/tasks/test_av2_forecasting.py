"""An Argoverse 2 motion-forecasting scenario through the pipeline's tasks: ingest by detection, alignment from
its tracks and map, motion/location queries, search, and the scripted edits refined on it like a Waymo Open
Motion scenario (hand-made scenario for the ingest task; the public sample end to end, skipped when
../shared/data is absent; no Prefect start)."""

from __future__ import annotations

from pathlib import Path

import pytest

from simsplat_core.data.registry import UnknownLogSourceError
from simsplat_core.eval.refinement.real import real_rows, scenario_of_log
from simsplat_core.eval.refinement.real_edits import evaluate_real_edits
from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.motion.registry import make_predictor
from storage import ArtifactStore, read_scene_log
from tasks.align import align_scene, train_motion_aligner
from tasks.logs import ingest_real_log
from tasks.query import answer_query
from tasks.search import search_store
from tests.simsplat_core.data.forecasting_files import SCENARIO_ID, write_scenario

SAMPLE = Path("av2") / "forecasting-0a1e6f0a"
SEQ = "0a1e6f0a-1817-4a98-b02e-db8c9327d151"


def test_ingest_task_detects_and_checks_options(tmp_path: Path) -> None:
    folder = write_scenario(tmp_path / "scenario")
    stored = ingest_real_log.fn(str(tmp_path / "store"), "auto", str(folder))
    assert stored.relpath == f"logs/{SCENARIO_ID}" and not stored.skipped
    assert stored.summary.source == "av2-forecasting" and stored.summary.num_frames == 20
    again = ingest_real_log.fn(str(tmp_path / "store"), "av2-forecasting", str(folder))
    assert again.skipped
    with pytest.raises(ValueError, match="'av2-forecasting' has no images to scale"):
        ingest_real_log.fn(str(tmp_path / "store"), "av2-forecasting", str(folder), image_scale=0.5)
    with pytest.raises(UnknownLogSourceError, match="unknown log source 'nuscenes'"):
        ingest_real_log.fn(str(tmp_path / "store"), "nuscenes", str(folder))


@pytest.fixture(scope="module")
def forecasting_store(shared_data, tmp_path_factory):
    """The public scenario ingested by detection into a fresh store, an aligner trained on it, its language scene."""
    store = ArtifactStore(tmp_path_factory.mktemp("forecasting-store"))
    stored = ingest_real_log.fn(store.root, "auto", str(shared_data / SAMPLE))
    assert stored.relpath == f"logs/{SEQ}" and stored.summary.source == "av2-forecasting"
    model = train_motion_aligner.fn(store.root, [SEQ], MotionAlignerConfig(epochs=20))
    aligned = align_scene.fn(store.root, SEQ, None, model.model_hash)
    return store, aligned


@pytest.mark.shared_data
def test_aligned_from_tracks_and_answers_motion_queries(forecasting_store) -> None:
    store, aligned = forecasting_store
    assert aligned.scene_hash == "" and aligned.metrics["object_nodes"] == 57
    assert aligned.metrics["nodes_with_motion"] >= 40

    crossing = answer_query(store.root, SEQ, "all pedestrians crossing in front of us")
    assert len(crossing.grounding.node_ids) >= 2 and crossing.png_uri == ""
    for nid in crossing.grounding.node_ids:
        node = crossing.scene.node(nid)
        assert node.category == "pedestrian"
        assert (node.motion.labels.motion, node.motion.labels.sector) == ("crossing", "in_front_of_ego")

    parked = answer_query(store.root, SEQ, "all parked cars behind us")
    assert len(parked.grounding.node_ids) >= 3
    assert all(parked.scene.node(n).motion.labels.motion == "parked" for n in parked.grounding.node_ids)

    (turning,) = answer_query(store.root, SEQ, "the vehicle turning left").grounding.node_ids
    assert crossing.scene.node(turning).motion.labels.motion == "turning_left"


@pytest.mark.shared_data
def test_search_finds_the_crossing(forecasting_store, tmp_path) -> None:
    store = forecasting_store[0]
    found = search_store(store.root, "a pedestrian crossing in front of us", out=str(tmp_path / "search"), top=1)
    assert found.hits and found.hits[0].seq_id == SEQ
    first, last = found.hits[0].window
    assert 0 <= first < last < 110 and Path(found.hits[0].picture).is_file()


@pytest.mark.shared_data
def test_rollouts_and_scripted_edits_refined(forecasting_store) -> None:
    store = forecasting_store[0]
    scenario = scenario_of_log(read_scene_log(store, SEQ, load_images=False))
    assert (scenario.dataset, scenario.states.num_steps, scenario.resampled) == ("av2-forecasting", 110, False)
    assert len(scenario.map.lanes) == 34 and scenario.map.context.has_drivable
    rows = {r["predictor"] or r["method"]: r for r in real_rows([scenario], [make_predictor("constant-velocity")]).rows}
    assert 0.05 < rows["constant-velocity"]["ade_3s"] < rows["constant-velocity"]["ade_8s"] < 5.0
    edited = evaluate_real_edits([scenario], make_predictor("reactive"), modes=("none", "full"))
    assert edited.applied[SEQ]["stopped_truck"] == ""  # applied; the others name why the scenario has no situation
    assert "no moving vehicle ahead" in edited.applied[SEQ]["lead_brakes"]
    by_mode = {r["method"]: r for r in edited.rows}
    assert set(by_mode) == {"none", "full"} and {r["dataset"] for r in edited.rows} == {"av2-forecasting+edits"}
    assert by_mode["full"]["failure"] <= by_mode["none"]["failure"]
