"""``simsplat deploy check`` on ``ray up`` cluster YAMLs: Ray's own validation and start commands that would leave
the workers without Ray."""

from __future__ import annotations

from pathlib import Path

import yaml

from flows.deploy_check import check_ray_cluster

RAY = Path(__file__).resolve().parents[2] / "deploy" / "ray-cluster.yaml"


def _broken(tmp_path: Path, change) -> Path:
    spec = yaml.safe_load(RAY.read_text())
    change(spec)
    path = tmp_path / "ray.yaml"
    path.write_text(yaml.safe_dump(spec))
    return path


def test_the_shipped_cluster_starts_the_autoscaler_on_the_head() -> None:
    assert check_ray_cluster(RAY) == []
    spec = yaml.safe_load(RAY.read_text())
    assert any("--autoscaling-config=" in command for command in spec["head_start_ray_commands"])


def test_a_head_without_the_autoscaler_is_named(tmp_path: Path) -> None:
    def drop_autoscaler(spec: dict) -> None:
        spec["head_start_ray_commands"] = [c.split(" --autoscaling-config")[0] for c in spec["head_start_ray_commands"]]

    path = _broken(tmp_path, drop_autoscaler)
    (finding,) = check_ray_cluster(path)
    assert (finding.file, finding.item, finding.field) == (str(path), "head", "head_start_ray_commands")
    assert "worker nodes" in finding.problem


def test_what_ray_up_refuses_is_named_with_its_field(tmp_path: Path) -> None:
    path = _broken(tmp_path, lambda spec: spec.update(setup_comands=["true"]))
    (finding,) = check_ray_cluster(path)
    assert finding.file == str(path) and "`ray up` refuses it" in finding.problem and "setup_comands" in finding.problem
    path = _broken(tmp_path, lambda spec: spec["auth"].update(ssh_user=7))
    (finding,) = check_ray_cluster(path)
    assert (finding.field, finding.problem.startswith("`ray up` refuses it")) == ("auth.ssh_user", True)
