"""``simsplat run | reconstruct | align``: make scenes from the store's logs (the main job and its stages)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from flows.cli.common import (
    CaptionerOption,
    IterationsOption,
    RunnerOption,
    WorkersOption,
    alignment_config,
    check_vlm,
    run_flow,
    stored_sequences,
    world_config,
    writable_store,
)
from flows.cli.printers import (
    print_artifacts,
    print_export,
    print_language,
    print_logs,
    print_mining,
    print_nothing_new,
    print_scenes,
    print_stages,
    print_tables,
)
from flows.runtime import RunnerKind

if TYPE_CHECKING:
    from flows.pipeline import ExportPlan, MiningPlan

commands = typer.Typer()


@commands.command()
def run(
    store: Annotated[
        str, typer.Option(help="Artifact store root: a local directory or an object-store URI.")
    ] = "artifacts",
    sequences: Annotated[
        int,
        typer.Option(
            min=0,
            help="Synthetic sequences to generate into the store first "
            "(0: only the logs already there; `make demo` asks for 2).",
        ),
    ] = 0,
    seed: Annotated[int, typer.Option(help="Seed of the first sequence; sequence i uses seed + i.")] = 0,
    frames: Annotated[int, typer.Option(min=2, help="Frames per sequence (10 Hz).")] = 40,
    width: Annotated[int, typer.Option(min=16)] = 240,
    height: Annotated[int, typer.Option(min=16)] = 160,
    runner: RunnerOption = RunnerKind.ray,
    workers: WorkersOption = None,
    iterations: IterationsOption = None,
    align: Annotated[bool, typer.Option(help="Run the language-alignment stage after reconstruction.")] = True,
    captioner: CaptionerOption = "builtin",
    mine: Annotated[int, typer.Option(min=0, help="After alignment, mine this many accepted scenarios per aligned "
                                      "sequence (logs without camera images on their tracks; 0: no mining, or "
                                      "the --mining-config file's count; the asset bank is built first when "
                                      "missing). Overrides the file's scenarios_per_log.")] = 0,
    vlm: Annotated[str | None, typer.Option(help="VLM client of the mining loop: rule (built-in, offline) or openai "
                                            "(SIMSPLAT_VLM_URL, SIMSPLAT_VLM_MODEL, SIMSPLAT_VLM_API_KEY). Overrides "
                                            "the --mining-config file's client (default: its client, else rule).")
                   ] = None,
    export: Annotated[str | None, typer.Option(help="With --mine or --mining-config: export the run's accepted "
                                               "scenarios as a dataset into EXPORT/<name>/ (the file's dataset "
                                               "name, else the run id; WOMD shards, ScenarioNet, Parquet; see "
                                               "`simsplat export`). Overrides the file's dataset folder.")] = None,
    mining_config: Annotated[Path | None, typer.Option(help="Mining configuration (YAML, versioned; e.g. "
                                                       "deploy/mining/nightly.yaml): saved searches seeding the "
                                                       "loop, edit categories and counts per log, attempts, seed, "
                                                       "the VLM client and its endpoint, the dataset appended to. "
                                                       "Mines after alignment; --mine, --vlm and --export override "
                                                       "its values.")] = None,
    landing: Annotated[str | None, typer.Option(help="Landing folder (path, file:// or object-store URI such as "
                                                "s3://bucket/prefix) scanned first for new "
                                                "logs of any registered source: each is ingested once, one that "
                                                "fails to load is quarantined with its reason.")] = None,
) -> None:
    """Run the main job over every log in the store (ingested real logs included), after generating
    --sequences synthetic ones: one reconstructed scene per log with camera images, then language
    alignment (motion aligner trained on every log + one queryable language scene per log; a log without
    images is aligned from its tracks and map), the grounding benchmark on the synthetic logs and, with --mine K
    or --mining-config FILE, scenario mining of every aligned log (K accepted scenarios per sequence, stored under
    STORE/edits/<run_id>/; a log without camera images is mined on its tracks, judged on the bird's-eye view and
    the trajectories) and, with --export DIR or the file's dataset, their export as a dataset for planner
    training. With --landing DIR, the logs in DIR not yet ingested are ingested first; one that fails to load is
    quarantined under STORE/landing/quarantine/ and not retried until it changes. A run with nothing new (no
    new landing log, the --sequences already stored alike, every stored log reconstructed, aligned and, when mining,
    mined before with the same settings) is recorded as such in seconds, without starting Prefect or Ray."""
    from flows.pipeline import idle_main_run, main_flow, reconstruction_config
    from tasks.answers import mining_as_dict

    alignment = alignment_config(captioner)
    mining, export_plan = run_mining_plans(mine, vlm, export, seed, mining_config)
    if landing is not None:
        check_landing(landing)
    elif sequences == 0:
        stored_sequences(store, param_hint="--sequences")
    params = dict(store_root=store, seeds=list(range(seed, seed + sequences)),
                  config=world_config(frames, width, height), reconstruction=reconstruction_config(iterations),
                  alignment=alignment, align=align,
                  mining=mining, export=export_plan, landing=landing)
    writable_store(store)  # last: a refused parameter leaves no store behind
    idle = idle_main_run(params)  # nothing new: recorded without starting Prefect or Ray
    if idle is not None:
        print_nothing_new(idle)
        return
    result = run_flow(main_flow, runner, workers, **params)
    print_logs(result.logs)
    print_stages(result.stages)
    if result.scenes:
        print_scenes(result.scenes)
    if result.language:
        print_language(result.aligner, result.language)
    if result.grounding is not None:
        from storage.runs import run_dir
        from tasks.run_tables import load_run_tables

        print_tables(load_run_tables(store, run_dir(result.run_id)))
    if result.mining:
        print_mining(mining_as_dict(result.run_id, result.mining))
    if result.export is not None:
        print_export(result.export)
    print_artifacts(store)


def run_mining_plans(mine: int, vlm: str | None, export: str | None, seed: int, mining_config: Path | None
                     ) -> tuple[MiningPlan | None, ExportPlan | None]:
    """The run's mining and export from the command line: ``--mining-config`` (``flows.pipeline.plans_from_config``,
    ``--mine``, ``--vlm`` and ``--export`` overriding the file), else ``--mine K`` with ``--vlm`` and ``--seed``;
    a bad parameter when the file is not valid, the client is unknown or unconfigured, or ``--export`` has nothing
    to export."""
    from flows.pipeline import ExportPlan, MiningPlan, plans_from_config
    from tasks.mining_config import MiningConfigError, load_mining_config

    if mining_config is not None:
        try:
            loaded = load_mining_config(mining_config)
        except MiningConfigError as exc:
            raise typer.BadParameter(str(exc), param_hint="--mining-config") from exc
        planned, export_plan = plans_from_config(loaded, per_sequence=mine or None, vlm=vlm, export_out=export)
        if planned.vlm != "openai" or planned.chat is None:  # an endpoint named in the file needs no environment
            check_vlm(planned.vlm)
        return planned, export_plan
    check_vlm(vlm or "rule")
    if export is not None and not mine:
        raise typer.BadParameter("--export exports mined scenarios: give --mine K or --mining-config FILE too (or "
                                 "run `simsplat export`)", param_hint="--export")
    mining = MiningPlan(mine, vlm=vlm or "rule", seed=seed) if mine else None
    return mining, ExportPlan(out=export) if export is not None else None


def check_landing(landing: str) -> None:
    """Fail before the run when the landing location cannot be scanned (``tasks.landing.check_landing``)."""
    from tasks.landing import check_landing

    try:
        check_landing(landing)
    except (ValueError, FileNotFoundError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--landing") from exc


@commands.command("align")
def align_command(
    store: Annotated[
        str, typer.Option(help="Artifact store root holding logs/<seq_id>/ (and scenes of logs with images).")
    ],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence to align (repeatable; default: every log).")] = None,
    runner: RunnerOption = RunnerKind.threads,
    workers: WorkersOption = None,
    captioner: CaptionerOption = "builtin",
) -> None:
    """Align language to stored logs: train (or reuse) the motion aligner on every log in the store, then
    build one queryable language scene per chosen log (through its newest reconstructed scene; a log without
    camera images from its tracks and map: motion and location language, no appearance)."""
    from flows.pipeline import align_flow
    from tasks.stages import plan_alignment

    alignment = alignment_config(captioner)
    try:
        plan_alignment(store, list(seq) if seq else None)  # fail before starting Prefect
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--seq") from exc
    result = run_flow(align_flow, runner, workers, store_root=store, seq_ids=list(seq) if seq else None,
                      alignment=alignment)
    print_stages(result.stages, ("reconstruct",))
    print_language(result.aligner, result.language)


@commands.command()
def reconstruct(
    store: Annotated[str, typer.Option(help="Artifact store root holding logs/<seq_id>/.")],
    seq: Annotated[
        list[str] | None, typer.Option(help="Sequence to reconstruct (repeatable; default: every log).")
    ] = None,
    iterations: IterationsOption = None,
    runner: RunnerOption = RunnerKind.threads,
    workers: WorkersOption = None,
) -> None:
    """Reconstruct stored logs into scene-graph Gaussian scenes under STORE/scenes/<seq_id>/<scene_hash>/."""
    from flows.pipeline import reconstruct_flow, reconstruction_config
    from tasks.stages import plan_stages

    seq_ids = stored_sequences(store, seq)
    scenes = run_flow(reconstruct_flow, runner, workers, store_root=store, seq_ids=seq_ids,
                      config=reconstruction_config(iterations))
    print_stages(plan_stages(store, seq_ids), ("reconstruct",))
    print_scenes(scenes)
