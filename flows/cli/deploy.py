"""``simsplat deploy check``: the deployment files under ``deploy/`` checked without a server or a cluster
(``flows.deploy_check``); exit code 1 with the findings listed when anything is wrong."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Annotated

import typer

from flows.cli.common import JsonOption
from flows.cli.printers import print_deploy_findings

commands = typer.Typer(help="Check the deployment files.", no_args_is_help=True)


@commands.command("check")
def check(
    file: Annotated[Path, typer.Option("--file", help="Prefect deployments (prefect.yaml).")] = Path(
        "deploy/prefect.yaml"),
    ray: Annotated[Path, typer.Option(help="Ray cluster YAML for `ray up`.")] = Path("deploy/ray-cluster.yaml"),
    kuberay: Annotated[Path, typer.Option(help="KubeRay RayCluster manifest.")] = Path(
        "deploy/kuberay-raycluster.yaml"),
    root: Annotated[Path | None, typer.Option(help="Folder the entry points are relative to (default: the working "
                                              "directory, as for `prefect deploy`).")] = None,
    as_json: JsonOption = False,
) -> None:
    """Every deployment's entry point imports and is a flow, its parameters fit the flow's signature and types, its
    cron schedules parse and its work pool is declared; the Ray cluster YAML has what `ray up` needs; the KubeRay
    manifest is a ray.io/v1 RayCluster whose head and worker containers have an image and resources."""
    from flows.deploy_check import check_deploy_files

    findings = check_deploy_files(file, ray, kuberay, root)
    if as_json:
        typer.echo(json.dumps([asdict(f) for f in findings]))
    else:
        print_deploy_findings(findings, [file, ray, kuberay])
    if findings:
        raise typer.Exit(1)
