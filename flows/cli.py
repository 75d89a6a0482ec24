"""The ``simsplat`` command line: one subcommand per job, each a thin call into a flow.

Run ``simsplat --help`` or ``simsplat COMMAND --help``.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Annotated, Optional

import typer
from rich.console import Console
from rich.table import Table

from flows.runtime import RunnerKind

# Our own loggers go to the Prefect UI too when they log inside a flow or task.
os.environ.setdefault("PREFECT_LOGGING_EXTRA_LOGGERS", "simsplat_core,storage,tasks,flows")
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")

app = typer.Typer(help="SIMSplat scenario-mining pipeline.", no_args_is_help=True, add_completion=False)
ingest_app = typer.Typer(help="Decode real driving logs into the artifact store.", no_args_is_help=True)
app.add_typer(ingest_app, name="ingest")
console = Console()
logger = logging.getLogger("flows.cli")

RunnerOption = Annotated[RunnerKind, typer.Option(help="Where per-sequence tasks run: a local Ray cluster or threads.")]
WorkersOption = Annotated[Optional[int], typer.Option(help="Parallel workers (default: all CPUs).")]


@app.callback()
def _configure(verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log INFO messages.")] = False) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")


def _run_flow(flow_fn, runner: RunnerKind, workers: int | None, **params):
    """Run ``flow_fn`` with the chosen task runner against one shared Prefect API."""
    from flows.runtime import make_task_runner, prefect_api

    with prefect_api():
        return flow_fn.with_options(task_runner=make_task_runner(runner, workers))(**params)


def _print_logs(logs) -> None:
    table = Table(title="Driving logs")
    for col in ("sequence", "source", "frames", "cameras", "objects", "MB", "seconds", ""):
        table.add_column(col)
    for s in logs:
        objects = ", ".join(f"{n} {c}" for c, n in s.summary.objects_by_category.items())
        table.add_row(s.summary.seq_id, s.summary.source, str(s.summary.num_frames), str(len(s.summary.cameras)),
                      objects, f"{s.bytes_on_disk / 1e6:.2f}", f"{s.seconds:.1f}", "skipped (up to date)" if s.skipped else "")
    console.print(table)


def _world_config(frames: int, width: int, height: int):
    from simsplat_core.world import WorldConfig

    return WorldConfig(num_frames=frames, width=width, height=height)


@app.command()
def run(
    store: Annotated[str, typer.Option(help="Artifact store root: a local directory or an object-store URI.")] = "artifacts",
    sequences: Annotated[int, typer.Option(min=1, help="Number of synthetic sequences.")] = 2,
    seed: Annotated[int, typer.Option(help="Seed of the first sequence; sequence i uses seed + i.")] = 0,
    frames: Annotated[int, typer.Option(min=2, help="Frames per sequence (10 Hz).")] = 40,
    width: Annotated[int, typer.Option(min=16)] = 240,
    height: Annotated[int, typer.Option(min=16)] = 160,
    runner: RunnerOption = RunnerKind.ray,
    workers: WorkersOption = None,
) -> None:
    """Run the main job on the embedded default data (synthetic sequences)."""
    from flows.pipeline import main_flow

    logs = _run_flow(main_flow, runner, workers, store_root=store, seeds=list(range(seed, seed + sequences)),
                     config=_world_config(frames, width, height))
    _print_logs(logs)
    console.print(f"Artifacts under [bold]{store}[/bold]: logs/<seq_id>/ (Parquet tables, EXR images).")


@app.command()
def world(
    out: Annotated[str, typer.Option(help="Artifact store root to write into.")],
    sequences: Annotated[int, typer.Option(min=1)] = 1,
    seed: Annotated[int, typer.Option()] = 0,
    frames: Annotated[int, typer.Option(min=2)] = 40,
    width: Annotated[int, typer.Option(min=16)] = 240,
    height: Annotated[int, typer.Option(min=16)] = 160,
    runner: RunnerOption = RunnerKind.threads,
    workers: WorkersOption = None,
) -> None:
    """Generate synthetic driving sequences into OUT/logs/<seq_id>/."""
    from flows.pipeline import generate_world_flow

    logs = _run_flow(generate_world_flow, runner, workers, store_root=out,
                     seeds=list(range(seed, seed + sequences)), config=_world_config(frames, width, height))
    _print_logs(logs)


def _ingest(source: str, path: Path, out: str, image_scale: float) -> None:
    from flows.pipeline import ingest_flow

    if not path.exists():
        raise typer.BadParameter(f"{path} does not exist", param_hint="PATH")
    logs = _run_flow(ingest_flow, RunnerKind.threads, 1, store_root=out, source=source, paths=[str(path)],
                     image_scale=image_scale)
    _print_logs(logs)


@ingest_app.command("waymo-frame")
def ingest_waymo_frame(
    path: Annotated[Path, typer.Argument(help="A Waymo Open Dataset Frame TFRecord file.")],
    out: Annotated[str, typer.Option(help="Artifact store root.")],
    image_scale: Annotated[float, typer.Option(min=0.01, max=1.0, help="Resize camera images by this factor "
                                               "(0.5: 960x640; a full-size 200-frame segment needs ~6 GB of RAM).")] = 0.5,
) -> None:
    """Decode a Waymo Frame TFRecord (all its records, one sequence) into OUT/logs/<seq_id>/."""
    _ingest("waymo-frame", path, out, image_scale)


@ingest_app.command("av2")
def ingest_av2(
    path: Annotated[Path, typer.Argument(help="An Argoverse 2 sensor log directory.")],
    out: Annotated[str, typer.Option(help="Artifact store root.")],
) -> None:
    """Decode an Argoverse 2 sensor log (annotations, poses, calibration, map) into OUT/logs/<seq_id>/."""
    _ingest("av2", path, out, 1.0)


@app.command()
def inspect(
    log_dir: Annotated[str, typer.Argument(help="A stored log: STORE/logs/<seq_id>.")],
    sheet: Annotated[Optional[Path], typer.Option(help="Write a contact sheet PNG (all cameras + bird's-eye view).")] = None,
    frame: Annotated[int, typer.Option(help="Frame shown on the contact sheet.")] = 0,
) -> None:
    """Summarise a stored log and optionally draw its projected 3D boxes on one frame."""
    import cv2

    from simsplat_core.summary import summarize_log
    from simsplat_core.viz.contact_sheet import contact_sheet
    from storage import ArtifactStore, read_scene_log

    root, seq_id = _split_log_dir(log_dir)
    log = read_scene_log(ArtifactStore(root), seq_id, load_images=sheet is not None)
    summary = summarize_log(log)
    table = Table(title=f"{summary.seq_id} ({summary.source})", show_header=False)
    table.add_row("frames", f"{summary.num_frames} over {summary.duration_s:.1f} s; test frames {summary.test_frames}")
    table.add_row("cameras", ", ".join(f"{c} {wh}" for c, wh in summary.cameras.items()) or "none")
    table.add_row("objects", ", ".join(f"{n} {c}" for c, n in summary.objects_by_category.items()) or "none")
    table.add_row("map", ", ".join(f"{n} {k}" for k, n in summary.map_by_kind.items()) or "none")
    console.print(table)
    if sheet is not None:
        image = contact_sheet(log, frame)
        sheet.parent.mkdir(parents=True, exist_ok=True)
        if not cv2.imwrite(str(sheet), cv2.cvtColor(image, cv2.COLOR_RGB2BGR)):
            raise typer.BadParameter(f"could not write {sheet}", param_hint="--sheet")
        console.print(f"contact sheet: {sheet}")


def _split_log_dir(log_dir: str) -> tuple[str, str]:
    """``STORE/logs/<seq_id>`` -> (``STORE``, ``seq_id``); URIs keep their scheme."""
    parts = log_dir.rstrip("/").rsplit("/", 2)
    if len(parts) != 3 or parts[1] != "logs" or not parts[2]:
        raise typer.BadParameter(f"expected STORE/logs/<seq_id>, got {log_dir!r}", param_hint="LOG_DIR")
    return parts[0] or "/", parts[2]


def main() -> None:
    app()


if __name__ == "__main__":
    main()
