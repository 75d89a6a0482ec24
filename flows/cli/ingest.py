"""``simsplat ingest waymo-frame | waymo-scenario | av2``: decode real driving logs into the artifact store."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flows.cli.common import run_flow
from flows.cli.printers import print_logs
from flows.runtime import RunnerKind

commands = typer.Typer(help="Decode real driving logs into the artifact store.", no_args_is_help=True)


def _ingest(source: str, path: Path, out: str, image_scale: float) -> None:
    from flows.pipeline import ingest_flow

    if not path.exists():
        raise typer.BadParameter(f"{path} does not exist", param_hint="PATH")
    logs = run_flow(
        ingest_flow, RunnerKind.threads, 1, store_root=out, source=source, paths=[str(path)], image_scale=image_scale
    )
    print_logs(logs)


@commands.command("waymo-frame")
def ingest_waymo_frame(
    path: Annotated[Path, typer.Argument(help="A Waymo Open Dataset Frame TFRecord file.")],
    out: Annotated[str, typer.Option(help="Artifact store root.")],
    image_scale: Annotated[
        float,
        typer.Option(min=0.01, max=1.0, help="Resize camera images by this factor "
                     "(0.5: 960x640; a full-size 200-frame segment needs ~6 GB of RAM)."),
    ] = 0.5,
) -> None:
    """Decode a Waymo Frame TFRecord (all its records, one sequence) into OUT/logs/<seq_id>/."""
    _ingest("waymo-frame", path, out, image_scale)


@commands.command("waymo-scenario")
def ingest_waymo_scenario(
    path: Annotated[Path, typer.Argument(help="A Waymo Open Motion Scenario TFRecord file.")],
    out: Annotated[str, typer.Option(help="Artifact store root.")],
) -> None:
    """Decode the first Scenario of a Waymo Open Motion TFRecord (tracks, ego, map; no images) into
    OUT/logs/<seq_id>/."""
    _ingest("waymo-scenario", path, out, 1.0)


@commands.command("av2")
def ingest_av2(
    path: Annotated[Path, typer.Argument(help="An Argoverse 2 sensor log directory.")],
    out: Annotated[str, typer.Option(help="Artifact store root.")],
) -> None:
    """Decode an Argoverse 2 sensor log (annotations, poses, calibration, map) into OUT/logs/<seq_id>/."""
    _ingest("av2", path, out, 1.0)
