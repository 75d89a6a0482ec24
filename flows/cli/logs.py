"""``simsplat world | inspect``: generate synthetic logs, look at a stored one."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flows.cli.common import RunnerOption, WorkersOption, run_flow, world_config
from flows.cli.printers import print_log_summary, print_logs
from flows.runtime import RunnerKind

commands = typer.Typer()


@commands.command()
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

    logs = run_flow(generate_world_flow, runner, workers, store_root=out,
                    seeds=list(range(seed, seed + sequences)), config=world_config(frames, width, height))
    print_logs(logs)


@commands.command()
def inspect(
    log_dir: Annotated[str, typer.Argument(help="A stored log: STORE/logs/<seq_id>.")],
    sheet: Annotated[
        Path | None, typer.Option(help="Write a contact sheet PNG (all cameras + bird's-eye view).")
    ] = None,
    frame: Annotated[int, typer.Option(help="Frame shown on the contact sheet.")] = 0,
) -> None:
    """Summarise a stored log and optionally draw its projected 3D boxes on one frame."""
    from tasks.inspect_log import inspect_log

    root, seq_id = split_log_dir(log_dir)
    try:
        summary, uri = inspect_log(root, seq_id, sheet, frame)
    except FileNotFoundError as exc:
        raise typer.BadParameter(str(exc), param_hint="LOG_DIR") from exc
    except (OSError, ValueError) as exc:
        raise typer.BadParameter(f"could not write {sheet}: {exc}", param_hint="--sheet") from exc
    print_log_summary(summary, uri)


def split_log_dir(log_dir: str) -> tuple[str, str]:
    """``STORE/logs/<seq_id>`` -> (``STORE``, ``seq_id``); URIs keep their scheme."""
    parts = log_dir.rstrip("/").rsplit("/", 2)
    if len(parts) != 3 or parts[1] != "logs" or not parts[2]:
        raise typer.BadParameter(f"expected STORE/logs/<seq_id>, got {log_dir!r}", param_hint="LOG_DIR")
    return parts[0] or "/", parts[2]
