"""Mining configuration files: the shipped one parses, a valid file becomes the run's mining and export plans (the
command line's overrides winning), every kind of bad field is an error naming the file and the field, the content key
follows the settings (not the comments or the description), and the API key is only ever named, never recorded."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from flows.pipeline import plans_from_config
from storage.run_records import json_safe
from tasks.mining_config import (
    FORMAT_VERSION,
    MiningConfigError,
    load_mining_config,
    mining_config_key,
    parse_mining_config,
)

REPO = Path(__file__).resolve().parents[2]
NIGHTLY = REPO / "deploy" / "mining" / "nightly.yaml"

VALID = {
    "version": 1,
    "description": "pedestrians first",
    "searches": {"queries": ["a pedestrian crossing in front of us while a car turns"], "variants_per_hit": 1,
                 "only_hits": True},
    "mining": {"scenarios_per_log": 2, "categories": ["add_pedestrian", "remove"], "max_attempts": 4, "seed": 7},
    "vlm": {"client": "openai", "endpoint": "http://127.0.0.1:9/v1", "model": "tiny-vlm",
            "api_key_env": "TEAM_VLM_KEY"},
    "dataset": {"name": "nightly", "formats": ["parquet"], "out": "/data/datasets"},
}


def _write(tmp_path: Path, data: object, name: str = "mining.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_shipped_nightly_config_parses() -> None:
    loaded = load_mining_config(NIGHTLY)
    assert loaded.source.version == FORMAT_VERSION and len(loaded.key) == 64
    assert loaded.config.searches.queries and loaded.config.dataset is not None


def test_a_valid_file_becomes_the_runs_plans_and_the_command_line_overrides_it(tmp_path: Path) -> None:
    loaded = load_mining_config(_write(tmp_path, VALID))
    mining, export = plans_from_config(loaded)
    assert (mining.per_sequence, mining.max_attempts, mining.vlm, mining.seed) == (2, 4, "openai", 7)
    assert mining.categories == ("add_pedestrian", "remove") and mining.only_hits and mining.variants_per_hit == 1
    assert mining.searches == ("a pedestrian crossing in front of us while a car turns",)
    assert mining.chat is not None and (mining.chat.base_url, mining.chat.model, mining.chat.api_key_env) == (
        "http://127.0.0.1:9/v1", "tiny-vlm", "TEAM_VLM_KEY")
    assert mining.config == loaded.source and loaded.source.path == str(tmp_path / "mining.yaml")
    assert export is not None and (export.out, export.name, export.formats) == ("/data/datasets", "nightly",
                                                                                 ("parquet",))
    # a named dataset takes every accepted scenario not yet in it: the same filters every run, so runs append
    assert export.config("run-a").filters == export.config("run-b").filters
    assert export.config("run-a").name == "nightly"

    overridden, moved = plans_from_config(loaded, per_sequence=5, vlm="rule", export_out="/elsewhere")
    assert (overridden.per_sequence, overridden.vlm, overridden.chat) == (5, "rule", None)  # no endpoint for rule
    assert moved is not None and (moved.out, moved.name) == ("/elsewhere", "nightly")
    bare = load_mining_config(_write(tmp_path, {"version": 1}, "bare.yaml"))
    assert plans_from_config(bare)[1] is None  # no dataset, no --export: no export
    assert plans_from_config(bare, export_out="/x")[1].name is None  # a dataset per run


@pytest.mark.parametrize(("section", "field", "value", "named"), [
    ("mining", "scenarios_per_log", 0, "mining.scenarios_per_log: "),
    ("mining", "max_attempts", "many", "mining.max_attempts: "),
    ("mining", "categories", ["add_truck"], "mining.categories: unknown edit category ['add_truck']"),
    ("mining", "categories", ["remove", "remove"], "mining.categories: repeated"),
    ("mining", "seeds", 3, "mining.seeds: unknown field"),
    ("searches", "queries", ["  "], "searches.queries: empty search description"),
    ("searches", "variants_per_hit", 0, "searches.variants_per_hit: "),
    ("vlm", "client", "gpt", "vlm.client: "),
    ("vlm", "endpoint", "127.0.0.1:8000", "vlm.endpoint: must start with http:// or https://"),
    ("dataset", "name", "my dataset", "dataset.name: dataset name 'my dataset'"),
    ("dataset", "formats", ["csv"], "dataset.formats: ['csv']"),
])
def test_every_bad_field_is_named_with_its_value(tmp_path: Path, section: str, field: str, value: object,
                                                named: str) -> None:
    data = json.loads(json.dumps(VALID))
    data[section][field] = value
    path = _write(tmp_path, data)
    with pytest.raises(MiningConfigError) as caught:
        load_mining_config(path)
    error = caught.value
    assert str(error).startswith(f"{path}: {named}") and error.file == str(path)
    assert error.field == f"{section}.{field}"
    assert repr(value) in str(error) or error.problem == "unknown field (a typo?)"


@pytest.mark.parametrize(("data", "field", "problem"), [
    ({"mining": {}}, "version", "missing"),
    ({"version": 2}, "version", "2 is not a supported version"),
    ({"version": True}, "version", "True is not a supported version"),
    ({"version": 1, "vlm": {"endpoint": "http://h/v1"}}, "vlm", "endpoint and model are for client: openai"),
    ({"version": 1, "dataset": {"formats": ["womd"]}}, "dataset.name", "Field required"),
    ([1, 2], "-", "not a mapping"),
])
def test_file_level_problems_are_named(tmp_path: Path, data: object, field: str, problem: str) -> None:
    path = _write(tmp_path, data)
    with pytest.raises(MiningConfigError) as caught:
        load_mining_config(path)
    assert (caught.value.field, caught.value.file) == (field, str(path)) and problem in caught.value.problem


def test_missing_and_non_yaml_files_are_named(tmp_path: Path) -> None:
    with pytest.raises(MiningConfigError, match=f"^{tmp_path / 'none.yaml'}: cannot read"):
        load_mining_config(tmp_path / "none.yaml")
    broken = tmp_path / "broken.yaml"
    broken.write_text("version: 1\nmining: [unclosed\n")
    with pytest.raises(MiningConfigError, match=f"^{broken}: not YAML"):
        load_mining_config(broken)


def test_the_content_key_follows_the_settings_not_the_wording_of_the_file(tmp_path: Path) -> None:
    key = load_mining_config(_write(tmp_path, VALID)).key
    reworded = dict(VALID, description="something else entirely")
    commented = tmp_path / "commented.yaml"
    commented.write_text("# the team's file\n" + yaml.safe_dump(reworded, default_flow_style=True))
    assert load_mining_config(commented).key == key == mining_config_key(parse_mining_config(VALID))
    changed = dict(VALID, mining={**VALID["mining"], "seed": 8})
    assert mining_config_key(parse_mining_config(changed)) != key


def test_the_api_key_is_named_never_recorded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    secret = "sk-live-0123456789abcdef"
    monkeypatch.setenv("TEAM_VLM_KEY", secret)
    loaded = load_mining_config(_write(tmp_path, VALID))
    mining, export = plans_from_config(loaded)
    recorded = json.dumps(json_safe({"mining": mining, "export": export}))  # what a run record keeps
    assert "TEAM_VLM_KEY" in recorded and secret not in recorded
    # a key pasted where its variable's name belongs is refused without repeating it
    pasted = json.loads(json.dumps(VALID))
    pasted["vlm"]["api_key_env"] = secret
    with pytest.raises(MiningConfigError) as caught:
        load_mining_config(_write(tmp_path, pasted, "pasted.yaml"))
    assert caught.value.field == "vlm.api_key_env" and secret not in str(caught.value)
