"""The files under deploy/ pass ``simsplat deploy check``, and each kind of mistake in a broken copy is one finding
naming the file, the deployment and the field."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from flows.cli import app
from flows.deploy_check import check_deploy_files, check_kuberay, check_prefect_file, check_ray_cluster

REPO = Path(__file__).resolve().parents[2]
DEPLOY = REPO / "deploy"
PREFECT, RAY, KUBERAY = DEPLOY / "prefect.yaml", DEPLOY / "ray-cluster.yaml", DEPLOY / "kuberay-raycluster.yaml"


def _write(path: Path, spec: dict) -> Path:
    path.write_text(yaml.safe_dump(spec))
    return path


def test_the_shipped_deployment_files_pass():
    assert check_deploy_files(PREFECT, RAY, KUBERAY, root=REPO) == []
    names = {d["name"] for d in yaml.safe_load(PREFECT.read_text())["deployments"]}
    assert {"nightly-mining", "dataset-generation", "evaluation"} <= names


def test_deploy_check_exits_0_on_the_shipped_files_and_1_with_the_findings_as_json(tmp_path, monkeypatch):
    monkeypatch.chdir(REPO)
    assert CliRunner().invoke(app, ["deploy", "check"]).exit_code == 0
    broken = yaml.safe_load(KUBERAY.read_text())
    broken["kind"] = "Pod"
    result = CliRunner().invoke(app, ["deploy", "check", "--kuberay", str(_write(tmp_path / "k.yaml", broken)),
                                      "--json"])
    assert result.exit_code == 1
    assert json.loads(result.stdout) == [{"file": str(tmp_path / "k.yaml"), "item": "-", "field": "kind",
                                          "problem": "'Pod' is not 'RayCluster'"}]


@pytest.mark.parametrize(("breakage", "field"), [
    ("unknown entrypoint", "entrypoint"),
    ("unaccepted parameter", "parameters.no_such_parameter"),
    ("missing required parameter", "parameters.store_root"),
    ("wrong parameter type", "parameters.sequences"),
    ("bad cron", "schedules[0].cron"),
    ("undeclared work pool", "work_pool.name"),
])
def test_each_broken_deployment_gives_one_finding_naming_file_deployment_and_field(tmp_path, breakage, field):
    spec = yaml.safe_load(PREFECT.read_text())
    nightly = next(d for d in spec["deployments"] if d["name"] == "nightly-mining")
    if breakage == "unknown entrypoint":
        nightly["entrypoint"] = "flows/pipeline.py:no_such_flow"
    elif breakage == "unaccepted parameter":
        nightly["parameters"]["no_such_parameter"] = 1
    elif breakage == "missing required parameter":
        del nightly["parameters"]["store_root"]
    elif breakage == "wrong parameter type":
        nightly["parameters"]["sequences"] = "eight"
    elif breakage == "bad cron":
        nightly["schedules"][0]["cron"] = "0 25 * * *"
    else:
        nightly["work_pool"]["name"] = "no-such-pool"
    path = _write(tmp_path / "prefect.yaml", spec)
    findings = check_prefect_file(path, root=REPO)
    assert [(f.file, f.item, f.field) for f in findings] == [(str(path), "nightly-mining", field)]


@pytest.mark.parametrize(("config", "problem"), [
    (None, "cannot read"),
    ({"version": 1, "mining": {"categories": ["add_truck"]}}, "mining.categories: unknown edit category"),
    ({"version": 3}, "version: 3 is not a supported version"),
])
def test_a_deployment_naming_a_bad_mining_config_is_a_finding_quoting_the_file_and_its_field(tmp_path, config,
                                                                                             problem):
    (tmp_path / "flows").symlink_to(REPO / "flows")  # entry points resolve under the root, so does the config
    spec = yaml.safe_load(PREFECT.read_text())
    nightly = next(d for d in spec["deployments"] if d["name"] == "nightly-mining")
    nightly["parameters"]["mining_config"] = "mining.yaml"
    if config is not None:
        _write(tmp_path / "mining.yaml", config)
    path = _write(tmp_path / "prefect.yaml", spec)
    (finding,) = check_prefect_file(path, root=tmp_path)
    assert (finding.item, finding.field) == ("nightly-mining", "parameters.mining_config")
    assert finding.problem.startswith(str(tmp_path / "mining.yaml")) and problem in finding.problem


def test_a_kuberay_manifest_without_head_group_and_a_ray_yaml_without_provider_are_named(tmp_path):
    kuberay = yaml.safe_load(KUBERAY.read_text())
    del kuberay["spec"]["headGroupSpec"]
    path = _write(tmp_path / "kuberay.yaml", kuberay)
    assert [(f.file, f.field) for f in check_kuberay(path)] == [(str(path), "spec.headGroupSpec")]
    ray = yaml.safe_load(RAY.read_text())
    del ray["provider"]
    path = _write(tmp_path / "ray.yaml", ray)
    assert (str(path), "provider") in [(f.file, f.field) for f in check_ray_cluster(path)]


def test_a_worker_container_without_resources_and_a_file_that_is_not_yaml_are_named(tmp_path):
    kuberay = yaml.safe_load(KUBERAY.read_text())
    del kuberay["spec"]["workerGroupSpecs"][0]["template"]["spec"]["containers"][0]["resources"]
    path = _write(tmp_path / "kuberay.yaml", kuberay)
    assert [f.field for f in check_kuberay(path)] == ["spec.workerGroupSpecs[0].template.spec.containers[0].resources"]
    bad = tmp_path / "bad.yaml"
    bad.write_text("deployments: [unclosed\n")
    assert [f.file for f in check_prefect_file(bad, root=REPO)] == [str(bad)]


def test_the_evaluation_flow_runs_eval_all_with_the_deployments_parameters(tmp_path, monkeypatch):
    import flows.evaluation as evaluation

    seen = {}
    monkeypatch.setattr(evaluation, "evaluate_all", lambda store, out_root, config: seen.update(
        store=store, out=out_root, config=config))
    evaluation.evaluation_flow.fn(str(tmp_path), only=["mining", "search"], per_sequence=2, clients=None, seed=4)
    config = seen["config"]
    assert (seen["store"], seen["out"]) == (str(tmp_path), None)
    assert (config.groups, config.per_sequence, config.clients, config.seed) == (("mining", "search"), 2, ("rule",), 4)
    with pytest.raises(ValueError, match="no driving log"):  # the real one, on an empty store
        monkeypatch.undo()
        evaluation.evaluation_flow.fn(str(tmp_path))
