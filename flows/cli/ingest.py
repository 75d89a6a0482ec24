"""``simsplat ingest SOURCE PATH --out DIR``: decode a real driving log into the artifact store.

SOURCE is a name of the log-source registry (``simsplat_core.data.registry``) or ``auto`` (the source that
recognises PATH); an unknown name lists the known ones with what they read.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flows.cli.common import run_flow
from flows.cli.printers import print_logs
from flows.runtime import RunnerKind

commands = typer.Typer()

#: ``--image-scale`` of ``simsplat ingest`` for sources with camera images, when not given.
DEFAULT_IMAGE_SCALE = 0.5


@commands.command("ingest", no_args_is_help=True)
def ingest(
    source: Annotated[str, typer.Argument(help="A log source of the registry (an unknown name lists them with "
                                          "what they read), or 'auto': the source that recognises PATH.")],
    path: Annotated[Path, typer.Argument(help="The log: the file or directory the source reads.")],
    out: Annotated[str, typer.Option(help="Artifact store root.")],
    image_scale: Annotated[
        float | None,
        typer.Option(min=0.01, max=1.0, help=f"Resize camera images by this factor, for sources with images "
                     f"(waymo-frame; default {DEFAULT_IMAGE_SCALE}: 960x640; a full-size 200-frame segment needs "
                     "~6 GB of RAM)."),
    ] = None,
) -> None:
    """Decode a real driving log of SOURCE at PATH into OUT/logs/<seq_id>/, e.g. simsplat ingest av2 LOG_DIR
    --out DIR, or simsplat ingest auto PATH --out DIR."""
    from flows.pipeline import ingest_flow
    from simsplat_core.data.registry import AUTO_SOURCE, UnknownLogSourceError, resolve_source

    if not path.exists():
        raise typer.BadParameter(f"{path} does not exist", param_hint="PATH")
    try:
        chosen = resolve_source(source, path)
    except UnknownLogSourceError as exc:
        raise typer.BadParameter(str(exc), param_hint="PATH" if source == AUTO_SOURCE else "SOURCE") from exc
    scales = "image_scale" in chosen.options
    if image_scale is not None and not scales:
        raise typer.BadParameter(f"log source {chosen.name!r} has no camera images to scale",
                                 param_hint="--image-scale")
    scale = (DEFAULT_IMAGE_SCALE if image_scale is None else image_scale) if scales else 1.0
    logs = run_flow(
        ingest_flow, RunnerKind.threads, 1, store_root=out, source=chosen.name, paths=[str(path)], image_scale=scale
    )
    print_logs(logs)
