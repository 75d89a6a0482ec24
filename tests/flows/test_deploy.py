"""deploy/prefect.yaml points at real flows with parameters they accept."""

from __future__ import annotations

import inspect
from pathlib import Path

import yaml
from prefect.flows import load_flow_from_entrypoint

DEPLOY = Path(__file__).resolve().parents[2] / "deploy" / "prefect.yaml"


def test_every_deployment_entrypoint_loads_and_accepts_its_parameters(monkeypatch):
    monkeypatch.chdir(DEPLOY.parents[1])
    spec = yaml.safe_load(DEPLOY.read_text())
    assert spec["deployments"]
    for deployment in spec["deployments"]:
        flow = load_flow_from_entrypoint(deployment["entrypoint"])
        accepted = set(inspect.signature(flow.fn).parameters)
        assert set(deployment["parameters"]) <= accepted, deployment["name"]
        for schedule in deployment.get("schedules", []):
            assert len(schedule["cron"].split()) == 5
