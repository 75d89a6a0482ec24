"""``simsplat export-rerun``: one stored scenario as a Rerun recording (``.rrd``) for the Rerun viewer
(``tasks.rerun_export``; needs the optional ``rerun-sdk`` package)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from flows.cli.common import JsonOption
from flows.cli.printers import report

if TYPE_CHECKING:
    from tasks.rerun_export import RecordingSummary

commands = typer.Typer()


def _print_recording(summary: RecordingSummary) -> None:
    typer.echo(f"{summary.path}: {summary.bytes / 1e6:.1f} MB, {summary.frames} frames, {summary.agents} agents, "
               f"{summary.images} camera images ({', '.join(summary.cameras) or 'no renders'}); open it with "
               "`rerun FILE`")


@commands.command("export-rerun")
def export_rerun(
    store: Annotated[str, typer.Option(help="Artifact store root holding the scenario.")],
    run: Annotated[str, typer.Option(help="The run of the edit (a mining run id, or manual).")],
    seq: Annotated[str, typer.Option(help="The edited sequence.")],
    edit: Annotated[str, typer.Option(help="The edit id (a folder under edits/RUN/SEQ/).")],
    out: Annotated[str, typer.Option(help="The .rrd file to write (replaced atomically).")],
    as_json: JsonOption = False,
) -> None:
    """Write one scenario as a Rerun recording: the road map, every agent's 3D box at each frame with its log and
    edited paths, and each camera's pose with the edit's render per frame. Open it with `rerun FILE`."""
    from storage.errors import MissingInputError
    from tasks.rerun_export import RerunUnavailableError, write_scenario_recording

    if not out.endswith(".rrd"):
        raise typer.BadParameter(f"--out {out!r}: the recording's file name must end in .rrd")
    try:
        summary = write_scenario_recording(store, run, seq, edit, out)
    except RerunUnavailableError as exc:
        raise typer.BadParameter(str(exc)) from exc
    except (MissingInputError, FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    report(summary, as_json, _print_recording)
