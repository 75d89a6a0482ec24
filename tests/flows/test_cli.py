"""The ``simsplat`` CLI: world generation, inspection, ingest of real logs, and error handling."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from flows.cli import app
from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, list_logs, list_scenes, read_scene_log, write_scene_log

runner = CliRunner()


def _tree_digest(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.mark.parametrize(
    "command",
    [
        [],
        ["run"],
        ["world"],
        ["ingest"],
        ["ingest", "waymo-frame"],
        ["ingest", "waymo-scenario"],
        ["ingest", "av2"],
        ["inspect"],
        ["reconstruct"],
        ["render"],
        ["query"],
        ["eval"],
        ["eval", "grounding"],
        ["eval", "editing"],
        ["align"],
        ["edit"],
    ],
)
def test_every_command_has_help(command):
    result = runner.invoke(app, [*command, "--help"])
    assert result.exit_code == 0, result.output
    assert "Usage" in result.output


@pytest.mark.orchestration
def test_world_then_inspect_writes_logs_and_contact_sheet(prefect_api_url, tmp_path):
    store = tmp_path / "store"
    result = runner.invoke(app, ["world", "--out", str(store), "--sequences", "2", "--seed", "5", "--frames", "6",
                                 "--width", "96", "--height", "64"])
    assert result.exit_code == 0, result.output
    assert list_logs(ArtifactStore(str(store))) == ["synth-000005", "synth-000006"]
    for name in ("frames", "tracks", "objects", "map_features"):
        assert (store / "logs" / "synth-000005" / f"{name}.parquet").is_file()
    assert list((store / "logs" / "synth-000005" / "images").rglob("*.exr"))

    sheet = tmp_path / "sheet.png"
    result = runner.invoke(
        app, ["inspect", str(store / "logs" / "synth-000005"), "--sheet", str(sheet), "--frame", "3"]
    )
    assert result.exit_code == 0, result.output
    assert "vehicle" in result.output and "front" in result.output
    image = cv2.imread(str(sheet))
    assert image is not None and image.shape[0] > 100 and image.std() > 5


def test_inspect_rejects_a_path_that_is_not_a_log(tmp_path):
    result = runner.invoke(app, ["inspect", str(tmp_path / "nowhere")])
    assert result.exit_code != 0
    assert "STORE/logs/<seq_id>" in result.output


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_ingest_av2_and_corrupt_waymo_leaves_store_unchanged(prefect_api_url, shared_data, tmp_path):
    store = tmp_path / "store"
    result = runner.invoke(
        app, ["ingest", "av2", str(shared_data / "av2" / "sensor-log-7fab2350"), "--out", str(store)]
    )
    assert result.exit_code == 0, result.output
    (seq_id,) = list_logs(ArtifactStore(str(store)))
    log = read_scene_log(ArtifactStore(str(store)), seq_id)
    assert len(log.tracks) == 114

    before = _tree_digest(store)
    corrupt = tmp_path / "corrupt.tfrecord"
    data = bytearray((shared_data / "waymo" / "pvps_data_one_frame.tfrecord").read_bytes())
    data[len(data) // 2] ^= 0xFF
    corrupt.write_bytes(bytes(data))
    result = runner.invoke(app, ["ingest", "waymo-frame", str(corrupt), "--out", str(store)])
    assert result.exit_code != 0
    assert "corrupt.tfrecord" in str(result.exception) + result.output
    assert _tree_digest(store) == before


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_ingest_waymo_scenario_reads_back(prefect_api_url, shared_data, tmp_path):
    store = ArtifactStore(str(tmp_path / "store"))
    sample = shared_data / "waymo" / "motion_data_one_scenario.tfrecord"
    result = runner.invoke(app, ["ingest", "waymo-scenario", str(sample), "--out", store.root])
    assert result.exit_code == 0, result.output
    assert list_logs(store) == ["637f20cafde22ff8"]
    log = read_scene_log(store, "637f20cafde22ff8")
    assert log.source == "waymo-scenario" and log.num_frames == 91 and not log.images
    assert len(log.tracks) == 82 and len(log.map_features) == 289
    np.testing.assert_array_equal(log.ego_poses[0], np.eye(4))
    assert log.metadata["current_time_index"] == "10" and "traffic_signals" in log.metadata


@pytest.mark.orchestration
def test_reconstruct_then_render_a_shifted_view(prefect_api_url, tmp_path):
    store = tmp_path / "store"
    world = WorldConfig(num_frames=4, width=64, height=48, test_every=2)
    write_scene_log(ArtifactStore(str(store)), generate_log(seed=3, config=world, seq_id="synth-000003"))
    command = ["reconstruct", "--store", str(store), "--iterations", "10", "--runner", "threads"]
    result = runner.invoke(app, command)
    assert result.exit_code == 0, result.output
    assert "synth-000003" in result.output and "Reconstructed scenes" in result.output
    (scene_hash,) = list_scenes(ArtifactStore(str(store)), "synth-000003")
    again = runner.invoke(app, [*command, "--seq", "synth-000003"])
    assert again.exit_code == 0 and "skipped" in again.output, again.output

    png = tmp_path / "views" / "left.png"
    result = runner.invoke(app, ["render", "--store", str(store), "--seq", "synth-000003", "--frame", "1",
                                 "--out", str(png), "--shift-left", "1", "--scene", scene_hash[:10]])
    assert result.exit_code == 0, result.output
    image = cv2.imread(str(png))
    assert image.shape == (48, 3 * 64 + 2 * 4, 3) and image.std() > 1
    front = tmp_path / "front.png"
    result = runner.invoke(app, ["render", "--store", str(store), "--seq", "synth-000003", "--frame", "1",
                                 "--out", str(front), "--camera", "front"])
    assert result.exit_code == 0, result.output
    assert cv2.imread(str(front)).shape == (48, 64, 3)
    assert not np.array_equal(cv2.imread(str(front)), image[:, :64])  # shifted view differs
    assert sorted(p.name for p in png.parent.iterdir()) == ["left.png"]  # no temporary left behind


def test_render_names_an_unknown_sequence_or_missing_scene(tmp_path):
    store = tmp_path / "store"
    result = runner.invoke(
        app, ["render", "--store", str(store), "--seq", "nope", "--frame", "0", "--out", str(tmp_path / "x.png")]
    )
    assert result.exit_code != 0
    assert "nope" in result.output
    write_scene_log(
        ArtifactStore(str(store)),
        generate_log(seed=0, config=WorldConfig(num_frames=2, width=32, height=24), seq_id="s0"),
    )
    result = runner.invoke(app, ["render", "--store", str(store), "--seq", "s0", "--frame", "0", "--out",
                                 str(tmp_path / "x.png")])
    assert result.exit_code != 0
    assert "no complete reconstructed scene" in result.output
    assert not (tmp_path / "x.png").exists()


def test_eval_grounding_names_what_is_missing(tmp_path):
    result = runner.invoke(app, ["eval", "grounding", "--store", str(tmp_path), "--out", str(tmp_path / "run")])
    assert result.exit_code != 0
    text = _flat(result.output)
    assert "no language scene" in text and "simsplat run" in text


def test_eval_editing_names_what_is_missing(tmp_path):
    result = runner.invoke(app, ["eval", "editing", "--store", str(tmp_path), "--out", str(tmp_path / "run")])
    assert result.exit_code != 0
    text = _flat(result.output)
    assert "no language scene" in text and "simsplat run" in text
    assert not (tmp_path / "run").exists()


def test_query_without_an_aligned_scene_says_so(tmp_path):
    result = runner.invoke(app, ["query", "--store", str(tmp_path), "--seq", "synth-000000", "the red car"])
    assert result.exit_code != 0
    assert "no language scene of 'synth-000000'" in _flat(result.output)


def _flat(output: str) -> str:
    """CLI output without rich's panel borders and line wrapping."""
    return " ".join(output.replace("│", " ").replace("╭", " ").replace("╰", " ").split())


def test_run_with_vlm_captioner_needs_an_endpoint_and_fails_before_any_work(tmp_path, monkeypatch):
    monkeypatch.delenv("SIMSPLAT_VLM_URL", raising=False)
    monkeypatch.delenv("SIMSPLAT_VLM_MODEL", raising=False)
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store"), "--captioner", "vlm"])
    assert result.exit_code != 0
    assert "SIMSPLAT_VLM_URL" in result.output and "--captioner" in result.output
    assert not (tmp_path / "store").exists()


def test_run_rejects_an_unknown_captioner(tmp_path):
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store"), "--captioner", "gpt"])
    assert result.exit_code != 0
    assert "captioner" in result.output and "builtin" in result.output
    assert not (tmp_path / "store").exists()


def test_run_names_a_bad_mining_config_and_an_export_without_mining_before_any_work(tmp_path, monkeypatch):
    config = tmp_path / "mining.yaml"
    config.write_text("version: 1\nmining:\n  categories: [add_truck]\n")
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store"), "--mining-config", str(config)])
    text = _flat(result.output)
    assert result.exit_code != 0 and "--mining-config" in text and "mining.categories" in text and "add_truck" in text
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store"), "--export", str(tmp_path / "out")])
    assert result.exit_code != 0 and "--mining-config" in _flat(result.output)
    monkeypatch.delenv("SIMSPLAT_VLM_URL", raising=False)
    config.write_text("version: 1\nvlm:\n  client: openai\n")  # no endpoint in the file nor the environment
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store"), "--mining-config", str(config)])
    assert result.exit_code != 0 and "SIMSPLAT_VLM_URL" in _flat(result.output)
    assert not (tmp_path / "store").exists()


def test_run_on_an_empty_store_without_sequences_says_how_to_add_logs(tmp_path):
    result = runner.invoke(app, ["run", "--store", str(tmp_path / "store")])
    assert result.exit_code != 0
    text = _flat(result.output)
    assert "no driving log" in text and "--sequences" in text and "simsplat ingest" in text
    assert not (tmp_path / "store").exists()


def test_align_names_an_unknown_sequence_before_starting_anything(tmp_path):
    store = tmp_path / "store"
    log = generate_log(seed=0, config=WorldConfig(num_frames=2, width=32, height=24), seq_id="s0")
    write_scene_log(ArtifactStore(str(store)), log)
    result = runner.invoke(app, ["align", "--store", str(store), "--seq", "nope"])
    assert result.exit_code != 0 and "nope" in _flat(result.output)
    result = runner.invoke(app, ["align", "--store", str(store)])  # images but no reconstruction yet
    assert result.exit_code != 0 and "simsplat reconstruct" in _flat(result.output)


@pytest.mark.orchestration
@pytest.mark.shared_data
def test_run_align_and_query_on_a_store_holding_only_the_av2_sample(prefect_api_url, shared_data, tmp_path):
    """Done-when of issue 9: `simsplat run` and `simsplat align` on an AV2-only store work end to end (no
    reconstruction: no camera images) and `simsplat query` answers motion / location queries."""
    from simsplat_core.data.av2 import load_av2_log

    store = tmp_path / "store"
    log = load_av2_log(shared_data / "av2" / "sensor-log-7fab2350")
    write_scene_log(ArtifactStore(str(store)), log)
    result = runner.invoke(app, ["run", "--store", str(store), "--runner", "threads", "--workers", "1"])
    assert result.exit_code == 0, result.output
    text = _flat(result.output)
    assert "reconstruct skipped: no camera images" in text and "Language scenes" in text
    assert list_scenes(ArtifactStore(str(store)), log.seq_id) == []
    aligner = re.search(r"motion aligner ([0-9a-f]{8})", text)
    assert aligner is not None

    result = runner.invoke(app, ["align", "--store", str(store), "--seq", log.seq_id])
    assert result.exit_code == 0, result.output
    # the aligner and the language scene are reused: the same model, still one language scene
    assert f"motion aligner {aligner.group(1)}" in _flat(result.output)
    assert len(list((store / "alignment").glob(f"*/scenes/{log.seq_id}/*"))) == 1

    result = runner.invoke(app, ["query", "--store", str(store), "--seq", log.seq_id,
                                 "the vehicle changing lanes to the left"])
    assert result.exit_code == 0, result.output
    assert "(node " in _flat(result.output) and "yes" in result.output  # one chosen node, named in the message


def test_run_on_a_store_that_cannot_be_written_fails_before_any_work(tmp_path):
    root = tmp_path / "store"
    root.write_text("a file, not a directory")
    result = runner.invoke(app, ["run", "--store", str(root), "--sequences", "1"])
    assert result.exit_code == 2  # a bad parameter, not a crash
    said = _flat(result.output)
    assert "--store" in said and "cannot write to the store" in said and "not a directory" in said
    assert "Traceback" not in result.output and root.read_text() == "a file, not a directory"
