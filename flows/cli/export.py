"""``simsplat export``: a store's accepted scenarios (or every edit, or the unedited logs) as a dataset for planner
training, in Waymo Open Motion shards, ScenarioNet pickles and Parquet (``tasks.export``)."""

from __future__ import annotations

from typing import Annotated

import typer

from flows.cli.common import JsonOption, option_names
from flows.cli.printers import print_export, report

commands = typer.Typer()


@commands.command("export")
def export(
    store: Annotated[str, typer.Option(help="Artifact store root to export from.")],
    out: Annotated[str | None, typer.Option(help="Folder the dataset goes in, as OUT/NAME/ (default: "
                                            "STORE/datasets/).")] = None,
    name: Annotated[str, typer.Option(help="The dataset's name (its folder under OUT). Exporting again with the "
                                      "same name and options adds the new scenarios only.")] = "scenarios",
    run: Annotated[list[str] | None, typer.Option(help="Edit runs to export (repeatable or comma separated; "
                                                  "default: every run).")] = None,
    fmt: Annotated[list[str] | None, typer.Option("--format", help="womd, scenarionet, parquet (repeatable or comma "
                                                  "separated; default: all three).")] = None,
    include: Annotated[str, typer.Option(help="accepted (mined scenarios the judge accepted), all-edits (every "
                                         "succeeded edit) or logs (the unedited logs).")] = "accepted",
    category: Annotated[list[str] | None, typer.Option(help="Edit categories to keep (repeatable or comma "
                                                       "separated; default: all).")] = None,
    min_plausibility: Annotated[int | None, typer.Option(min=1, max=5, help="Keep scenarios the judge rated at "
                                                         "least this plausible.")] = None,
    split: Annotated[str, typer.Option(help="Splits by source log: NAME=FRACTION pairs.")] = "train=0.8,val=0.2",
    steps: Annotated[int, typer.Option(min=1, help="Steps per scenario (WOMD: 91).")] = 91,
    current_index: Annotated[int, typer.Option(min=0, help="Last history step (WOMD: 10).")] = 10,
    hz: Annotated[float, typer.Option(min=0.1, help="Steps per second (WOMD: 10).")] = 10.0,
    stride: Annotated[int | None, typer.Option(min=1, help="Steps between windows of a longer log (default: the "
                                               "future horizon, steps - current-index - 1).")] = None,
    keep_failing: Annotated[bool, typer.Option("--keep-failing", help="Also export scenarios whose re-validation "
                                               "fails (they are reported either way).")] = False,
    seq: Annotated[list[str] | None, typer.Option(help="With --include logs: the logs to export (default: all).")]
    = None,
    as_json: JsonOption = False,
) -> None:
    """Export scenarios as a dataset planners train on: OUT/NAME/ with womd/ (Scenario TFRecord shards),
    scenarionet/ (pickles + dataset_summary.pkl), parquet/ (tables, and a torch Dataset over them), a manifest
    and a data card. Splits are by source log; a second export of a grown store adds only the new scenarios."""
    from flows.progress import StepBars
    from simsplat_core.export.windows import ExportLayout
    from storage.datasets import DatasetConflictError
    from storage.inventory import MissingInputError
    from tasks.export import ExportConfig, export_dataset, parse_splits
    from tasks.export_inputs import ExportFilters
    from tasks.progress import StepProgress

    try:
        filters = ExportFilters(include=include, runs=option_names(run), categories=option_names(category),
                                min_plausibility=min_plausibility, sequences=option_names(seq))
        config = ExportConfig(name=name, formats=option_names(fmt) or ExportConfig().formats, filters=filters,
                              splits=parse_splits(split), keep_failing=keep_failing,
                              layout=ExportLayout(steps=steps, current_index=current_index, hz=hz, stride=stride))
        with StepBars(headline=""):
            result = export_dataset(store, out, config, progress=StepProgress(f"export {name}", headline=""))
    except (MissingInputError, DatasetConflictError, FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    report(result, as_json, print_export)
