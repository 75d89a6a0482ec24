"""The ``simsplat`` command line: one subcommand per job, each a thin call into a flow.

Run ``simsplat --help`` or ``simsplat COMMAND --help``.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import os
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from flows.runtime import RunnerKind

# Our own loggers go to the Prefect UI too when they log inside a flow or task.
os.environ.setdefault("PREFECT_LOGGING_EXTRA_LOGGERS", "simsplat_core,storage,tasks,flows")
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")
os.environ.setdefault("PREFECT_LOGGING_TO_API_WHEN_MISSING_FLOW", "ignore")  # CLI work outside flows logs locally

app = typer.Typer(help="SIMSplat scenario-mining pipeline.", no_args_is_help=True, add_completion=False)
eval_app = typer.Typer(help="Evaluate stored results and write the run's tables.", no_args_is_help=True)
app.add_typer(eval_app, name="eval")
assets_app = typer.Typer(help="The asset bank of scene editing: build it, list it, draw its contact sheet.",
                         no_args_is_help=True)
app.add_typer(assets_app, name="assets")
console = Console()
logger = logging.getLogger("flows.cli")

VLMOption = Annotated[str, typer.Option(help="VLM client of the mining loop: rule (built-in, offline) or openai "
                                        "(SIMSPLAT_VLM_URL, SIMSPLAT_VLM_MODEL, SIMSPLAT_VLM_API_KEY).")]
RunnerOption = Annotated[RunnerKind, typer.Option(help="Where per-sequence tasks run: a local Ray cluster or threads.")]
WorkersOption = Annotated[int | None, typer.Option(help="Parallel workers (default: all CPUs).")]
IterationsOption = Annotated[int | None, typer.Option(min=1, help="Reconstruction iterations per sequence "
                                                         "(default: the ReconstructionConfig default).")]


@app.callback()
def _configure(verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log INFO messages.")] = False) -> None:
    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s"
    )


def _run_flow(flow_fn, runner: RunnerKind, workers: int | None, **params):
    """Run ``flow_fn`` with the chosen task runner against one shared Prefect API.

    With the threads runner, tasks' step progress (e.g. reconstruction iterations) is drawn live.
    """
    from flows.progress import StepBars
    from flows.runtime import make_task_runner, prefect_api

    with prefect_api(), StepBars():
        return flow_fn.with_options(task_runner=make_task_runner(runner, workers))(**params)


def _print_logs(logs) -> None:
    table = Table(title="Driving logs")
    for col in ("sequence", "source", "frames", "cameras", "MB", "seconds", "status"):
        table.add_column(col, no_wrap=True)
    table.add_column("objects")
    for s in logs:
        objects = ", ".join(f"{n} {c}" for c, n in s.summary.objects_by_category.items())
        table.add_row(s.summary.seq_id, s.summary.source, str(s.summary.num_frames), str(len(s.summary.cameras)),
                      f"{s.bytes_on_disk / 1e6:.1f}", f"{s.seconds:.1f}", "skipped" if s.skipped else "written",
                      objects)
    console.print(table)


def _print_scenes(scenes) -> None:
    table = Table(title="Reconstructed scenes (PSNR/SSIM on held-out test frames)")
    for col in ("sequence", "scene", "PSNR dB", "SSIM", "Gaussians", "seconds", ""):
        table.add_column(col, no_wrap=True)
    for s in scenes:
        m = s.metrics
        table.add_row(s.seq_id, s.scene_hash[:8], f"{m.get('psnr_test', float('nan')):.2f}",
                      f"{m.get('ssim_test', float('nan')):.3f}", str(int(m.get("num_gaussians", 0))),
                      f"{s.seconds:.1f}", "skipped" if s.skipped else "")
    console.print(table)


def _world_config(frames: int, width: int, height: int):
    from simsplat_core.world import WorldConfig

    return WorldConfig(num_frames=frames, width=width, height=height)


def _print_stages(stages, only: tuple[str, ...] | None = None) -> None:
    """The stages (``only`` those, when given) each log skipped, and why (nothing when none was skipped)."""
    skipped = [(p.seq_id, stage, reason) for p in stages
               for stage, reason in (p.skipped(only) if only else p.skipped()).items()]
    if not skipped:
        return
    table = Table(title="Stages skipped")
    for col in ("sequence", "stage", "why"):
        table.add_column(col, no_wrap=True)
    for seq_id, stage, reason in skipped:
        table.add_row(seq_id, stage, f"skipped: {reason}")
    console.print(table)


def _alignment_config(captioner: str):
    """The validated ``AlignmentConfig`` of ``--captioner`` (a VLM endpoint is checked now, not after hours)."""
    from simsplat_core.language.alignment.scene_builder import AlignmentConfig, AlignmentConfigError
    from simsplat_core.vlm import OpenAIChatConfig, VLMError

    try:
        alignment = AlignmentConfig(captioner=captioner).validate()
        if captioner == "vlm":
            OpenAIChatConfig.from_env()
    except (AlignmentConfigError, VLMError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--captioner") from exc
    return alignment


CaptionerOption = Annotated[str, typer.Option(
    help="Object captioner of the alignment: 'builtin' (offline) or 'vlm' (an OpenAI-compatible server "
         "from SIMSPLAT_VLM_URL / SIMSPLAT_VLM_MODEL; key in SIMSPLAT_VLM_API_KEY).")]


@app.command()
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
    mine: Annotated[int, typer.Option(min=0, help="After alignment, mine this many accepted scenarios per sequence "
                                      "with a reconstructed scene (0: no mining; the asset bank is built first "
                                      "when missing).")] = 0,
    vlm: VLMOption = "rule",
) -> None:
    """Run the main job over every log in the store (ingested real logs included), after generating
    --sequences synthetic ones: one reconstructed scene per log with camera images, then language
    alignment (motion aligner trained on every log + one queryable language scene per log; a log without
    images is aligned from its tracks and map), the grounding benchmark on the synthetic logs and, with --mine K,
    scenario mining (K accepted scenarios per sequence, stored under STORE/edits/<run_id>/)."""
    from flows.pipeline import MiningPlan, main_flow, reconstruction_config
    from storage import ArtifactStore, list_logs

    alignment = _alignment_config(captioner)
    _check_vlm(vlm)
    if sequences == 0 and not list_logs(ArtifactStore(store)):
        raise typer.BadParameter(
            f"no driving log in {store}/logs: pass --sequences N to generate synthetic ones, "
            "or ingest real ones first (simsplat ingest av2 / waymo-frame / waymo-scenario)",
            param_hint="--sequences",
        )
    result = _run_flow(main_flow, runner, workers, store_root=store, seeds=list(range(seed, seed + sequences)),
                       config=_world_config(frames, width, height), reconstruction=reconstruction_config(iterations),
                       alignment=alignment, align=align, mining=MiningPlan(mine, vlm=vlm, seed=seed) if mine else None)
    _print_logs(result.logs)
    _print_stages(result.stages)
    if result.scenes:
        _print_scenes(result.scenes)
    if result.language:
        _print_language(result.aligner, result.language)
    if result.grounding is not None:
        _print_grounding(result.grounding)
    if result.mining:
        _print_mining(_mining_as_dict(result.run_id, result.mining))
    console.print(f"Artifacts under [bold]{store}[/bold]: logs/<seq_id>/ (Parquet tables, EXR images), "
                  "scenes/<seq_id>/<scene_hash>/ (Gaussians, nodes, poses, metrics, test renders), "
                  "alignment/<model_hash>/ (motion aligner, language scenes).")


@app.command("align")
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
    from flows.pipeline import align_flow, plan_alignment

    alignment = _alignment_config(captioner)
    try:
        plan_alignment(store, list(seq) if seq else None)  # fail before starting Prefect
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--seq") from exc
    result = _run_flow(align_flow, runner, workers, store_root=store, seq_ids=list(seq) if seq else None,
                       alignment=alignment)
    _print_stages(result.stages, ("reconstruct",))
    _print_language(result.aligner, result.language)


def _print_language(aligner, scenes) -> None:
    table = Table(title=f"Language scenes (motion aligner {aligner.model_hash[:8]})")
    for col in ("sequence", "objects", "app", "motion", "mask IoU", "seconds", ""):
        table.add_column(col, no_wrap=True)
    for s in scenes:
        m = s.metrics
        table.add_row(s.seq_id, str(int(m.get("object_nodes", 0))), str(int(m.get("nodes_with_f_app", 0))),
                      str(int(m.get("nodes_with_motion", 0))), f"{m.get('mask_pooled_iou', float('nan')):.3f}",
                      f"{s.seconds:.1f}", "skipped" if s.skipped else "")
    console.print(table)


@app.command()
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
    from tasks.stages import plan_stages, resolve_seq_ids

    try:
        seq_ids = resolve_seq_ids(store, list(seq) if seq else None)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--seq") from exc
    scenes = _run_flow(reconstruct_flow, runner, workers, store_root=store, seq_ids=seq_ids,
                       config=reconstruction_config(iterations))
    _print_stages(plan_stages(store, seq_ids), ("reconstruct",))
    _print_scenes(scenes)


@app.command()
def render(
    store: Annotated[str, typer.Option(help="Artifact store root.")],
    seq: Annotated[str, typer.Option(help="Sequence whose reconstructed scene to render.")],
    frame: Annotated[int, typer.Option(min=0, help="Frame index to render.")],
    out: Annotated[str, typer.Option(help="PNG to write (cameras side by side).")],
    camera: Annotated[list[str] | None, typer.Option(help="Camera to render (repeatable; default: all).")] = None,
    shift_left: Annotated[
        float, typer.Option(help="Move the cameras this many metres to the ego's left (negative: right).")
    ] = 0.0,
    shift_forward: Annotated[float, typer.Option(help="Move the cameras this many metres forward (ego frame).")] = 0.0,
    scene: Annotated[str | None, typer.Option(help="Scene hash (or unique prefix); default: the newest scene.")] = None,
) -> None:
    """Render a stored scene at one frame from the log's cameras, optionally shifted in the ego frame."""
    from simsplat_core.scene import SceneGraph
    from simsplat_core.scene_view import render_views, shifted_cameras, side_by_side
    from storage import ArtifactStore, list_logs, read_scene, read_scene_log
    from storage.png import write_png

    artifacts = ArtifactStore(store)
    available = list_logs(artifacts)
    if seq not in available:
        raise typer.BadParameter(f"no complete log {seq!r} in {artifacts.uri('logs')}; available: {available}",
                                 param_hint="--seq")
    log = read_scene_log(artifacts, seq, load_images=False)
    try:
        loaded = read_scene(artifacts, seq, scene)
        views = shifted_cameras(log, frame, camera, shift_left=shift_left, shift_forward=shift_forward)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    images = render_views(SceneGraph.from_records(loaded.records), frame, views)
    uri = write_png(out, side_by_side(images))
    console.print(f"{seq} frame {frame} (scene {loaded.scene_hash[:12]}, shift left {shift_left:g} m, "
                  f"forward {shift_forward:g} m): {uri}")


@app.command()
def query(
    text: Annotated[
        str, typer.Argument(help='A free-form description, e.g. "the black car turning left at the intersection".')
    ],
    store: Annotated[str, typer.Option(help="Artifact store root holding aligned scenes (alignment/...).")],
    seq: Annotated[str, typer.Option(help="Sequence to search.")],
    out: Annotated[str | None, typer.Option(help="PNG to write: the matched masks over the cameras and the "
                                               "relevance maps (default: STORE/queries/<seq>/<query>.png).")] = None,
    frame: Annotated[int | None, typer.Option(min=0, help="Frame shown (default: where the match is largest).")] = None,
    top: Annotated[int, typer.Option(min=1, help="Candidates listed.")] = 5,
    as_json: Annotated[bool, typer.Option("--json", help="Print the answer as one JSON object on stdout (for "
                                          "scripts): query, matches, ranking (--top), message, picture.")] = False,
) -> None:
    """Ground a description to scene-graph nodes of a stored, aligned scene; print them and write a PNG
    (no PNG for a log without camera images)."""
    from tasks.query import answer_as_dict, answer_query

    try:
        answer = answer_query(store, seq, text, out=out, frame=frame)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(answer_as_dict(answer, top), allow_nan=False))
        return
    grounding = answer.grounding
    table = Table(title=f"{seq}: {text!r}")
    for column in ("rank", "node", "object", "category", "caption", "motion", "score", "app", "mot", "loc", "chosen"):
        table.add_column(column)
    chosen = set(grounding.node_ids)
    for rank, match in enumerate(grounding.ranking[:top], start=1):
        node = answer.scene.node(match.node_id)
        motion = node.motion.motion if node.motion is not None else "-"
        caption = node.caption.text if node.caption is not None else "-"
        table.add_row(str(rank), str(match.node_id), match.object_id, node.category, caption, motion,
                      f"{match.score:.3f}", *(f"{v:.2f}" for v in (match.appearance, match.motion, match.location)),
                      "yes" if match.node_id in chosen else "")
    console.print(table)
    console.print(grounding.message)
    if answer.png_uri:
        console.print(f"frame {answer.frame}: {answer.png_uri}")


@app.command()
def edit(
    store: Annotated[str, typer.Option(help="Artifact store root holding the sequence's aligned scene "
                                       "(and an asset bank for inserts and replacements).")],
    seq: Annotated[str, typer.Option(help="Sequence to edit.")],
    prompt: Annotated[str | None, typer.Argument(help='What to change, e.g. "remove the white van and make the '
                                                 'red car stop" (optional with --commands).')] = None,
    commands: Annotated[Path | None, typer.Option(help="EditProgram JSON (or a list of EditCommands) to apply "
                                                  "instead of parsing the prompt.")] = None,
    run_id: Annotated[str | None, typer.Option(help="Run the edit belongs to: edits/<run_id>/ (default: "
                                               "'manual').")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout (for scripts): status, "
                                          "edit directory, commands, grounded object ids, validation.")] = False,
    no_refine: Annotated[bool, typer.Option("--no-refine", help="Do not refine the traffic: every agent the edit "
                                            "did not change replays its log (deterministic editing).")] = False,
    predictor: Annotated[str, typer.Option(help="Motion predictor of refinement: reactive (default), "
                                           "constant-velocity, log.")] = "reactive",
    ego_replays: Annotated[bool, typer.Option("--ego-replays", help="Keep the ego on its log (renders from the "
                                              "log's camera poses) instead of letting it react to the edit.")] = False,
) -> None:
    """Edit a stored scene from language (or a command file): ground, apply, let the traffic react (multi-agent
    refinement), validate, render every frame and camera, and store the edit under
    STORE/edits/<run_id>/<seq>/<edit_id>/ (bev.png and bev.mp4 show log and refined paths). Exit code 1:
    refused; 2: bad command file."""
    from flows.bars import new_bar, want_bar
    from simsplat_core.editing.options import DEFAULT_OPTIONS
    from simsplat_core.motion.registry import make_predictor
    from storage import ArtifactStore, list_logs
    from tasks.edit import edit_as_dict, load_edit_context, run_edit

    try:
        motion_predictor = make_predictor(predictor)
    except KeyError as exc:
        raise typer.BadParameter(str(exc.args[0]), param_hint="--predictor") from exc
    options = dataclasses.replace(DEFAULT_OPTIONS, refinement="none" if no_refine else "full",
                                  ego_reacts=not (no_refine or ego_replays))
    if prompt is None and commands is None:
        raise typer.BadParameter("give a PROMPT or --commands FILE.json", param_hint="PROMPT")
    artifacts = ArtifactStore(store)
    available = list_logs(artifacts)
    if seq not in available:
        raise typer.BadParameter(f"no complete log {seq!r} in {artifacts.uri('logs')}; available: {available}",
                                 param_hint="--seq")
    commands_json = None
    if commands is not None:
        try:
            commands_json = commands.read_text(encoding="utf-8")
        except OSError as exc:
            raise typer.BadParameter(f"cannot read {commands}: {exc}", param_hint="--commands") from exc
    try:
        loaded = load_edit_context(artifacts, seq, predictor=motion_predictor)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    bar = new_bar() if want_bar() and not as_json else None
    task = bar.add_task(f"render {seq}", total=None) if bar is not None else None

    def progress(done: int, total: int) -> None:
        if bar is not None and task is not None:
            bar.update(task, completed=done, total=total)

    if bar is not None:
        bar.start()
    try:
        result = run_edit(store, seq, prompt or "", commands_json=commands_json, commands_source=str(commands),
                          run_id=run_id, loaded=loaded, progress=progress, options=options)
    finally:
        if bar is not None:
            bar.stop()
    code = 0 if result.status == "succeeded" else 2 if result.reason == "invalid_command" else 1
    if as_json:
        typer.echo(json.dumps(edit_as_dict(result, loaded.ctx.graph), allow_nan=False))
        raise typer.Exit(code)
    _print_edit(result, loaded.ctx.graph)
    raise typer.Exit(code)


def _print_edit(result, graph) -> None:
    from tasks.edit import edit_as_dict

    data = edit_as_dict(result, graph)
    console.print(f"{result.seq_id}: {result.prompt!r}", soft_wrap=True)
    if result.program is not None:
        for k, command in enumerate(result.program.commands):
            compact = command.model_dump(mode="json", exclude_defaults=True, exclude={"note"})
            console.print(f"  command {k + 1}: {json.dumps(compact, separators=(',', ':'))}", markup=False,
                          soft_wrap=True)
    if result.status != "succeeded":
        console.print(f"[bold red]{result.status}[/bold red] ({result.reason}): {result.message}", soft_wrap=True)
        return
    for grounded, change in zip(data["grounded"], data["changes"]):
        found = [f"{o} (node {n})" for o, n in zip(grounded["target_object_ids"], grounded["target_node_ids"])]
        anchors = [f"{o} (node {n})" for o, n in zip(grounded["anchor_object_ids"], grounded["anchor_node_ids"])]
        if found:
            console.print(f"  grounded target: {', '.join(found)}", markup=False, soft_wrap=True)
        if anchors:
            console.print(f"  grounded anchor: {', '.join(anchors)}", markup=False, soft_wrap=True)
        console.print(f"  changed: {change}", markup=False, soft_wrap=True)
    reaction = data.get("refinement")
    if reaction:
        reacted = ", ".join(reaction["refined"]) or "nobody"
        console.print(f"  traffic ({reaction['mode']}, {reaction['predictor']}): reacted: {reacted}", markup=False,
                      soft_wrap=True)
        by_reason: dict[str, list[str]] = {}
        for oid, why in reaction["replayed"].items():
            by_reason.setdefault(why, []).append(oid)
        for why, oids in by_reason.items():
            console.print(f"  replay their log ({why}): {', '.join(oids)}", markup=False, soft_wrap=True)
    validation = data["validation"]
    verdict = "[green]ok[/green]" if validation["ok"] else "[bold yellow]problems[/bold yellow]"
    console.print(f"validation of {validation['checked']} edited / reacting agent(s): {verdict}")
    for line in validation["failures"]:
        console.print(f"  - {line}", markup=False, soft_wrap=True)
    total = result.bytes.get("total", 0)
    timing = ", ".join(f"{k} {v:.1f}" for k, v in result.seconds.items() if k != "total")
    console.print(f"edit {result.edit_id}{' (already stored)' if result.skipped else ''}: {result.edit_uri} "
                  f"({total / 1e6:.2f} MB) in {result.seconds.get('total', 0.0):.1f} s ({timing})", markup=False,
                  soft_wrap=True)


def _check_vlm(vlm: str) -> None:
    """``--vlm`` names a known client, and ``openai`` has its endpoint configured (else a BadParameter)."""
    from simsplat_core.vlm.openai_chat import OpenAIChatConfig, VLMError
    from tasks.mine import VLM_KINDS

    if vlm not in VLM_KINDS:
        raise typer.BadParameter(f"unknown VLM client {vlm!r}; choose one of {list(VLM_KINDS)}", param_hint="--vlm")
    if vlm == "openai":
        try:
            OpenAIChatConfig.from_env()
        except VLMError as exc:
            raise typer.BadParameter(str(exc), param_hint="--vlm") from exc


@app.command()
def mine(
    store: Annotated[str, typer.Option(help="Artifact store root with aligned scenes and an asset bank "
                                       "(`simsplat assets build`).")],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence to mine (repeatable; default: every aligned log).")
                   ] = None,
    per_sequence: Annotated[int, typer.Option(min=1, help="Accepted scenarios wanted per sequence.")] = 3,
    max_attempts: Annotated[int, typer.Option(min=1, help="Attempts per proposal (the first plus adjusted "
                                              "retries).")] = 3,
    vlm: VLMOption = "rule",
    seed: Annotated[int, typer.Option(help="Seed of the mining loop (and of the rule-based client).")] = 0,
    run_id: Annotated[str | None, typer.Option(help="Run the scenarios belong to: edits/<run_id>/ (default: a new "
                                               "mine-<time> id).")] = None,
    from_search: Annotated[str | None, typer.Option(help='Seed the loop from a search of the logs: mine only the '
                                                    'sequences where this description holds, trying variants of '
                                                    'what each hit\'s subject does first, e.g. "a pedestrian '
                                                    'crossing in front of us".')] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout: the accepted scenarios, "
                                          "per-sequence summaries and totals.")] = False,
) -> None:
    """Mine scenarios automatically: a VLM (or the rule-based stand-in) proposes edits from the rendered scene, the
    editor executes them, the VLM judges the result, parameters are adjusted and retried; accepted scenarios are
    stored as edits under STORE/edits/<run_id>/<seq>/<edit_id>/, every attempt as a row of the run's edits table."""
    from flows.progress import StepBars
    from simsplat_core.vlm.openai_chat import VLMError
    from storage import ArtifactStore
    from storage.assets import list_asset_banks
    from storage.runs import new_run_id
    from tasks.mine import mine_sequence_task

    _check_vlm(vlm)
    seq_ids = _aligned_sequences(store, seq)
    artifacts = ArtifactStore(store)
    if not list_asset_banks(artifacts):
        raise typer.BadParameter(f"no asset bank in {artifacts.uri('assets')} (run `simsplat assets build --store "
                                 f"{store}` first)", param_hint="--store")
    seeds: dict[str, list] = {}
    if from_search is not None:
        from tasks.search import search_seeds

        try:
            found, seeds = search_seeds(store, from_search, seq_ids=seq_ids)
        except (FileNotFoundError, ValueError) as exc:
            raise typer.BadParameter(str(exc), param_hint="--from-search") from exc
        if not seeds:
            raise typer.BadParameter(f"nothing to seed the loop with: {found.message}", param_hint="--from-search")
        seq_ids = [s for s in seq_ids if s in seeds]
        logger.info("--from-search %r: %s; mining %s", from_search, found.message, seq_ids)
    run_id = run_id or new_run_id("mine")
    summaries = []
    try:
        with StepBars(headline=""):
            for i, seq_id in enumerate(seq_ids):  # the sequences take the edit categories in turn
                summaries.append(mine_sequence_task.fn(store, seq_id, run_id, per_sequence=per_sequence,
                                                       max_attempts=max_attempts, vlm=vlm, seed=seed,
                                                       seed_prompts=seeds.get(seq_id, ()),
                                                       category_offset=i * per_sequence))
    except (FileNotFoundError, VLMError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    data = _mining_as_dict(run_id, summaries)
    if as_json:
        typer.echo(json.dumps(data, allow_nan=False))
        return
    _print_mining(data)


def _mining_as_dict(run_id: str, summaries) -> dict:
    """``simsplat mine --json``: ``run_id``, ``edits_table``, ``scenarios`` (the accepted ones), ``sequences``
    (per-sequence summaries) and ``totals``."""
    from dataclasses import asdict

    sequences = [{k: v for k, v in asdict(s).items() if k != "scenarios"} for s in summaries]
    for entry in sequences:
        entry["seconds"] = {k: round(v, 3) for k, v in entry["seconds"].items()}
    categories: dict[str, int] = {}
    for s in summaries:
        for category, n in s.per_category.items():
            categories[category] = categories.get(category, 0) + n
    attempts = sum(s.attempts for s in summaries)
    accepted = sum(s.accepted for s in summaries)
    return {"run_id": run_id, "edits_table": summaries[0].edits_table if summaries else None,
            "scenarios": [asdict(sc) for s in summaries for sc in s.scenarios], "sequences": sequences,
            "totals": {"sequences": len(summaries), "attempts": attempts, "accepted": accepted,
                       "per_category": dict(sorted(categories.items()))}}


def _print_mining(data: dict) -> None:
    table = Table(title=f"Scenarios mined (run {data['run_id']})")
    for col in ("sequence", "prompt", "category", "attempts", "plausibility", "edit dir"):
        table.add_column(col)
    for sc in data["scenarios"]:
        plaus = "" if sc["plausibility"] is None else str(sc["plausibility"])
        table.add_row(sc["seq_id"], sc["prompt"], sc["category"], str(sc["attempts"]), plaus, sc["edit_dir"])
    console.print(table)
    totals = data["totals"]
    per = ", ".join(f"{k} {v}" for k, v in totals["per_category"].items()) or "none"
    console.print(f"{totals['accepted']} accepted of {totals['attempts']} attempt(s) in {totals['sequences']} "
                  f"sequence(s) ({per}); every attempt: {data['edits_table']}", markup=False, soft_wrap=True)


@eval_app.command("grounding")
def eval_grounding(
    store: Annotated[str, typer.Option(help="Artifact store root with synthetic logs and aligned scenes.")],
    out: Annotated[str, typer.Option(help="Run directory: tables/*.parquet + tables/*.md + manifest.json.")],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence (repeatable; default: every aligned log).")] = None,
) -> None:
    """Grounding benchmark (SIMSplat Tables 2 and 3): paraphrased queries from the logs' ground truth,
    accuracy and vIoU per category for the baselines, this method and its feature ablation."""
    from tasks.grounding_eval import evaluate_grounding_run

    seq_ids = _aligned_sequences(store, seq)
    try:
        result = evaluate_grounding_run.fn(store, seq_ids, out)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    _print_grounding(result)


def _aligned_sequences(store: str, seq: list[str] | None) -> list[str]:
    """``seq`` (default: every log of ``store`` with a language scene); a bad parameter naming the ones without."""
    from storage import ArtifactStore, list_logs
    from storage.language_scenes import list_language_scenes

    artifacts = ArtifactStore(store)
    aligned = [s for s in list_logs(artifacts) if list_language_scenes(artifacts, s)]
    seq_ids = list(seq) if seq else aligned
    missing = [s for s in seq_ids if s not in aligned]
    if missing or not seq_ids:
        raise typer.BadParameter(f"no language scene for {missing or 'any log'} in {store}; aligned: {aligned} "
                                 "(run `simsplat run` or the alignment stage first)", param_hint="--seq")
    return seq_ids


def _print_grounding(result) -> None:
    from simsplat_core.eval.grounding.metrics import CATEGORIES

    table = Table(title=f"Grounding on {len(result.seq_ids)} sequences, {result.queries} queries (acc / vIoU)")
    table.add_column("method")
    for category in CATEGORIES:
        table.add_column(category)
    for method, per in result.scores.items():
        table.add_row(method, *(f"{per[c]['acc']:.3f} / {per[c]['viou']:.3f}" for c in CATEGORIES))
    console.print(table)
    for name, uri in result.tables.items():
        console.print(f"{name}: {uri}")


@eval_app.command("editing")
def eval_editing(
    store: Annotated[str, typer.Option(help="Artifact store root with synthetic logs, aligned scenes and an asset "
                                       "bank (`simsplat assets build`).")],
    out: Annotated[str, typer.Option(help="Run directory: tables/*.parquet + tables/*.md + manifest.json.")],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence (repeatable; default: every aligned log).")] = None,
    per_category: Annotated[int, typer.Option(min=1, help="Prompts per category of Table 3, over all sequences.")] = 30,
    infeasible: Annotated[int, typer.Option(min=0, help="Infeasible prompts (they must be refused).")] = 20,
    methods: Annotated[list[str] | None, typer.Option(help="ours / chatsim-like / omnire-like (repeatable or comma "
                                                      "separated; default: all).")] = None,
    render_all: Annotated[bool, typer.Option("--render-all", help="Render every frame of every edit (default: the "
                                             "test frames and the frames where the edit is seen).")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the prompt set.")] = 0,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as one JSON object on stdout.")] = False,
) -> None:
    """Language editing benchmark (SIMSplat Table 3): prompts written from the synthetic worlds' ground truth,
    each edit checked against ground truth (trajectories, renders, captions), completion per category for this
    editor and the ChatSim-like / OmniRe-like variants, infeasible prompts refused, and edit fidelity against the
    world's own rendering of each edit."""
    from flows.progress import StepBars
    from tasks.editing_eval import evaluate_editing_run

    seq_ids = _aligned_sequences(store, seq)
    names = [n.strip() for m in methods or () for n in m.split(",") if n.strip()] or None
    try:
        with StepBars(headline=""):
            result = evaluate_editing_run.fn(store, seq_ids, out, per_category=per_category, infeasible=infeasible,
                                             methods=names, render_all=render_all, seed=seed)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    _report(result, as_json, _print_editing)


def _report(result, as_json: bool, printer: Callable[[Any], None]) -> None:
    """An evaluation's result: one JSON object on stdout (``--json``, dataclass fields) or ``printer``'s tables."""
    if as_json:
        from dataclasses import asdict

        typer.echo(json.dumps(asdict(result), default=float))
        return
    printer(result)


def _print_editing(result) -> None:
    from simsplat_core.eval.editing.prompts import CATEGORIES

    table = Table(title=f"Editing on {len(result.seq_ids)} sequences, {result.prompts['total']} prompts "
                        f"(+{result.prompts['infeasible']} infeasible): task completion")
    table.add_column("method")
    for category in (*CATEGORIES, "total"):
        table.add_column(category)
    table.add_column("infeasible refused")
    for method, per in result.completion.items():
        table.add_row(method, *(f"{per.get(c, float('nan')):.2f}" for c in (*CATEGORIES, "total")),
                      f"{result.refused.get(method, float('nan')):.2f}")
    console.print(table)
    fid = Table(title="Edit fidelity vs the world's rendering of the edit (PSNR dB; unedited test PSNR)")
    for col in ("method", *CATEGORIES, "total", "unedited"):
        fid.add_column(col)
    for method, per in result.fidelity.items():
        fid.add_row(method, *(f"{per[c]['psnr']:.2f}" for c in (*CATEGORIES, "total")),
                    f"{per['total']['psnr_unedited']:.2f}")
    console.print(fid)
    for method, stats in result.edit_seconds.items():
        if stats:
            console.print(f"{method}: one edit {stats['median']:.2f} s median, {stats['max']:.2f} s max")
    for name, uri in result.tables.items():
        console.print(f"{name}: {uri}")


@eval_app.command("mining")
def eval_mining(
    store: Annotated[str, typer.Option(help="Artifact store root with aligned scenes and an asset bank; the mined "
                                       "scenarios are stored in it under edits/evalmine-<client>-<time>/.")],
    out: Annotated[str, typer.Option(help="Run directory: tables/*.parquet + tables/*.md + manifest.json.")],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence (repeatable; default: every aligned log).")] = None,
    per_sequence: Annotated[int, typer.Option(min=1, help="Accepted scenarios wanted per sequence.")] = 3,
    max_attempts: Annotated[int, typer.Option(min=1, help="Attempts per proposal.")] = 3,
    clients: Annotated[str, typer.Option(help="VLM clients, comma separated: rule, openai (run only when "
                                         "SIMSPLAT_VLM_URL and SIMSPLAT_VLM_MODEL are set).")] = "rule,openai",
    seed: Annotated[int, typer.Option(help="Seed of the mining loop (and of the rule-based client).")] = 0,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as one JSON object on stdout.")] = False,
) -> None:
    """Mining benchmark (SIMSplat Table 5 analogue): mine every sequence per VLM client; completion, mean attempts
    to acceptance, mean plausibility, accepted scenarios re-checked for collisions and off-road agents, acceptance
    by edit category, where the time goes (accepted scenarios per hour per core), and the search benchmark of the same
    sequences (tables/search: RefAV timestamp and log balanced accuracy per query)."""
    from flows.progress import StepBars
    from tasks.mining_eval import evaluate_mining_run
    from tasks.search_eval import search_run_table

    seq_ids = _aligned_sequences(store, seq)
    names = [n.strip() for n in clients.split(",") if n.strip()]
    try:
        with StepBars(headline=""):
            result = evaluate_mining_run.fn(store, seq_ids, out, clients=names, per_sequence=per_sequence,
                                            max_attempts=max_attempts, seed=seed, search_table=search_run_table)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    _report(result, as_json, _print_mining_eval)


def _print_mining_eval(result) -> None:
    table = Table(title=f"Mining on {len(result.seq_ids)} sequence(s)")
    columns = ("client", "prompts", "accepted", "completion", "attempts_mean", "plausibility_mean",
               "accepted_with_failure", "note")
    for col in columns:
        table.add_column(col)
    for row in result.mining:
        table.add_row(*(f"{row[c]:.2f}" if isinstance(row[c], float) else str(row[c]) for c in columns))
    console.print(table)
    for row in result.stages:
        if row["stage"] == "total":
            console.print(f"{row['client']}: {row['seconds']:.0f} s, {row['accepted_per_hour_per_core']:.1f} "
                          f"accepted scenarios per hour per core ({result.cores} core(s))")
    for line in result.failed_scenarios:
        console.print(f"accepted but failing on re-check: {line}", markup=False, soft_wrap=True)
    for name, uri in result.tables.items():
        console.print(f"{name}: {uri}")

#: Real driving-log samples beside the repository (``../shared/data``), the default of ``eval motion --real``.
SHARED_REAL_LOGS: tuple[str, ...] = ("waymo/motion_data_one_scenario.tfrecord", "av2/sensor-log-7fab2350")


def default_real_logs(root: Path | None = None) -> list[Path]:
    """The real-log samples under ``<repo>/../shared/data`` that exist (none when it is absent)."""
    base = (root if root is not None else Path(__file__).resolve().parents[1]).parent / "shared" / "data"
    return [base / rel for rel in SHARED_REAL_LOGS if (base / rel).exists()]


@eval_app.command("motion")
def eval_motion(
    out: Annotated[str, typer.Option(help="Run directory: tables/motion.{parquet,md}, "
                                     "tables/motion_outcomes.{parquet,md} + manifest.json.")],
    store: Annotated[str | None, typer.Option(help="Artifact store root with aligned synthetic scenes and an asset "
                                              "bank: the edit-based (synthetic) rows.")] = None,
    seq: Annotated[list[str] | None, typer.Option(help="Scene of --store (repeatable; default: every aligned "
                                                  "log).")] = None,
    real: Annotated[list[Path] | None, typer.Option(help="A Waymo Open Motion scenario TFRecord or an Argoverse 2 "
                                                    "log directory (repeatable; default: the samples under "
                                                    "../shared/data when present).")] = None,
    predictor: Annotated[list[str] | None, typer.Option(help="Predictors rolled out on the real logs: reactive / "
                                                        "constant-velocity / log (repeatable or comma separated; "
                                                        "default: every available one).")] = None,
    edit_predictor: Annotated[str, typer.Option(help="Predictor that refines the edits (synthetic and scripted "
                                                "real edits).")] = "reactive",
    no_real_edits: Annotated[bool, typer.Option("--no-real-edits", help="Skip the scripted edits of the real "
                                                "logs.")] = False,
    per_category: Annotated[int, typer.Option(min=1, help="Editing-benchmark prompts per category (insert / "
                                              "modify), over all scenes.")] = 30,
    per_kind: Annotated[int, typer.Option(min=0, help="Interaction prompts of each kind per scene.")] = 3,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as one JSON object on stdout.")] = False,
) -> None:
    """Multi-agent refinement (issue 11): the ``motion`` table. Synthetic rows: the editing benchmark's insert /
    modify prompts and interaction prompts applied to the store's scenes with refinement none / single-agent /
    full; real rows: the predictors rolled out on real logs (the ego replays its log, every other agent is
    predicted from 1.1 s of history) against the logged future; real edit rows: scripted edits of the real logs
    (lead vehicle brakes, stopped truck, jaywalker) in every mode. Columns: collision, off-road, kinematic and
    overall failure rates (per scenario and per agent), progress, stopped agents, ADE at 3 s and 8 s."""
    from flows.progress import StepBars
    from simsplat_core.data.errors import CorruptLogError
    from simsplat_core.motion.registry import available_predictors
    from tasks.motion_eval import evaluate_motion_run

    names = [n.strip() for p in predictor or () for n in p.split(",") if n.strip()] or [
        n for n in available_predictors() if n != "log"]
    seq_ids = _aligned_sequences(store, seq) if store is not None else []
    if seq and store is None:
        raise typer.BadParameter("--seq needs --store", param_hint="--seq")
    paths = list(real) if real else default_real_logs()
    if not paths and not seq_ids:
        raise typer.BadParameter("no real logs given and no samples under ../shared/data", param_hint="--real")
    try:
        with StepBars(headline=""):
            result = evaluate_motion_run.fn(out, paths, names, store_root=store, seq_ids=seq_ids,
                                            edit_predictor=edit_predictor, real_edits=not no_real_edits,
                                            per_category=per_category, per_kind=per_kind)
    except CorruptLogError as exc:
        raise typer.BadParameter(f"damaged log: {exc}", param_hint="--real") from exc
    except KeyError as exc:
        raise typer.BadParameter(str(exc.args[0]) if exc.args else str(exc), param_hint="--predictor") from exc
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--real") from exc
    _report(result, as_json, _print_motion)


def _print_motion(result) -> None:
    from simsplat_core.eval.refinement.table import MOTION_COLUMNS

    table = Table(title=f"Motion on {len(result.sequences)} scene(s) and {len(result.real)} real log(s): failure "
                        "rates, progress, ADE (m)")
    names = [n for n, _, _ in MOTION_COLUMNS]
    for name in names:
        table.add_column(name)
    for row in result.rows:
        table.add_row(*("" if row[n] is None else f"{row[n]:.3f}" if isinstance(row[n], float) else str(row[n])
                        for n in names))
    console.print(table)
    for seq_id, edits in result.real_edits.items():
        console.print(f"real edits of {seq_id}: " + "; ".join(f"{e} applied" if not why else f"{e}: {why}"
                                                             for e, why in edits.items()))
    console.print(f"motion: {result.table}")


BankOption = Annotated[str | None, typer.Option("--bank", help="Bank hash (or unique prefix); default: the newest.")]


@assets_app.command("build")
def assets_build(
    store: Annotated[str, typer.Option(help="Artifact store root with reconstructed scenes (scenes/<seq_id>/...).")],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence to cut assets out of (repeatable; default: every "
                                                  "reconstructed one).")] = None,
    sheet: Annotated[bool, typer.Option(help="Draw the contact sheet into the bank directory.")] = True,
    as_json: Annotated[bool, typer.Option("--json", help="Print the result as one JSON object on stdout.")] = False,
) -> None:
    """Build the asset bank: vehicles and pedestrians cut out of every reconstructed scene (those good enough;
    pedestrians keep their gait) plus procedural static objects, under STORE/assets/<bank_hash>/. The same
    inputs give the same bank hash: a built bank is not built again."""
    from flows.progress import StepBars
    from tasks.assets import build_asset_bank

    try:
        with StepBars(headline=""):
            built = build_asset_bank.fn(store, list(seq) if seq else None, sheet=sheet)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--seq") from exc
    if as_json:
        typer.echo(json.dumps({"bank_hash": built.bank_hash, "uri": built.uri, "assets": built.assets,
                               "by_category": built.by_category, "gaussians": built.gaussians, "bytes": built.bytes,
                               "skipped": built.skipped, "sheet": built.sheet_uri or None,
                               "seconds": round(built.seconds, 3), "report": built.report}))
        return
    for line in built.report:
        console.print(line, markup=False, highlight=False)
    counts = ", ".join(f"{n} {c}" for c, n in sorted(built.by_category.items()))
    status = "already built, skipped" if built.skipped else f"built in {built.seconds:.1f} s"
    console.print(f"asset bank {built.bank_hash[:12]}: {built.assets} assets ({counts}), {built.gaussians} Gaussians, "
                  f"{built.bytes / 1e6:.1f} MB; {status}\n  {built.uri}")
    if built.sheet_uri:
        console.print(f"contact sheet: {built.sheet_uri}")


@assets_app.command("list")
def assets_list(
    store: Annotated[str, typer.Option(help="Artifact store root.")],
    bank: BankOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the banks and the assets as one JSON object.")] = False,
) -> None:
    """List the stored asset banks and the assets of one (the newest unless --bank)."""
    from storage import ArtifactStore
    from storage.assets import list_asset_banks, read_asset_index, read_bank_manifest

    artifacts = ArtifactStore(store)
    try:
        bank_hash, rows = read_asset_index(artifacts, bank)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--bank") from exc
    banks = [{"bank_hash": h, **{k: (read_bank_manifest(artifacts, h) or {}).get(k) for k in
                                  ("assets", "by_category", "written_at")}} for h in list_asset_banks(artifacts)]
    if as_json:
        typer.echo(json.dumps({"banks": banks, "bank_hash": bank_hash, "assets": rows}))
        return
    listing = Table(title=f"Asset banks in {artifacts.uri('assets')}")
    for col in ("bank", "assets", "by category", "written"):
        listing.add_column(col, no_wrap=True)
    for b in banks:
        listing.add_row(b["bank_hash"][:12] + (" *" if b["bank_hash"] == bank_hash else ""), str(b["assets"]),
                        ", ".join(f"{n} {c}" for c, n in sorted((b["by_category"] or {}).items())),
                        str(b["written_at"] or ""))
    console.print(listing)
    table = Table(title=f"Assets of bank {bank_hash[:12]}")
    for col in ("asset", "category", "subtype", "colour", "caption", "size m", "Gaussians", "source"):
        table.add_column(col)
    for r in rows:
        source = f"{r['source_seq']} {r['source_object']}".strip() or "procedural"
        table.add_row(r["asset_id"], r["category"], r["subtype"], r["color"], r["caption"],
                      " x ".join(f"{v:.2f}" for v in r["size"]), str(r["num_gaussians"]), source)
    console.print(table)


@assets_app.command("sheet")
def assets_sheet(
    store: Annotated[str, typer.Option(help="Artifact store root.")],
    out: Annotated[str, typer.Option(help="PNG to write.")],
    bank: BankOption = None,
    columns: Annotated[int, typer.Option(min=1, help="Tiles per row.")] = 8,
) -> None:
    """Draw a bank's contact sheet: every asset rendered alone from the same 3/4 view, with its caption."""
    from flows.progress import StepBars
    from simsplat_core.viz.asset_sheet import asset_contact_sheet
    from storage import ArtifactStore
    from storage.assets import read_asset_bank
    from storage.png import write_png
    from tasks.progress import StepProgress

    try:
        assets_bank = read_asset_bank(ArtifactStore(store), bank)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--bank") from exc
    tiles = StepProgress("contact sheet", headline="")
    with StepBars(headline=""):
        picture = asset_contact_sheet(assets_bank.assets, columns=columns, progress=lambda done, n: tiles(done, n))
    uri = write_png(out, picture)
    console.print(f"contact sheet of bank {assets_bank.bank_hash[:12]} ({len(assets_bank)} assets): {uri}")


# ------------------------------------------------------------------------------------------- search (issue 12)
@app.command()
def search(
    text: Annotated[str, typer.Argument(help='A description, e.g. "a pedestrian crossing in front of ego while a car '
                                              'turns right".')],
    store: Annotated[str, typer.Option(help="Artifact store root holding logs (aligned ones give colours and "
                                            "camera pictures).")],
    seq: Annotated[list[str] | None, typer.Option(help="Sequence to search (repeatable; default: every log).")] = None,
    top: Annotated[int, typer.Option(min=1, help="Hits listed and drawn.")] = 10,
    out: Annotated[str | None, typer.Option(help="Folder for the hit pictures (default: STORE/searches/<query>/).")
                   ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the hits as one JSON object (seq_id, object_ids, "
                                          "window [start, end], score, picture).")] = False,
) -> None:
    """Find where a description holds in the store's logs: objects and frame windows, ranked, a picture per hit
    (cameras with the matched objects outlined for aligned logs, else a bird's-eye view)."""
    from tasks.search import search_as_dict, search_store

    try:
        found = search_store(store, text, seq_ids=seq, top=top, out=out)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(search_as_dict(found), allow_nan=False))
        return
    table = Table(title=f"search: {text!r}")
    for column in ("rank", "sequence", "objects", "frames", "score", "picture"):
        table.add_column(column)
    for rank, hit in enumerate(found.hits, start=1):
        table.add_row(str(rank), hit.seq_id, ", ".join(hit.object_ids), f"{hit.window[0]}-{hit.window[1]}",
                      f"{hit.score:.2f}", hit.picture or "-")
    console.print(table)
    console.print(found.message)


@eval_app.command("search")
def eval_search_command(
    store: Annotated[list[str], typer.Option(help="Store(s) of synthetic logs (repeatable: several stores give the "
                                                 "log-level figure more logs).")],
    out: Annotated[str, typer.Option(help="Where tables/search.{parquet,md} go.")],
) -> None:
    """Search's RefAV balanced accuracies (timestamp and log level) on the query set over synthetic logs."""
    from tasks.search_eval import evaluate_search

    try:
        summary = evaluate_search(store, out)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    console.print(summary)


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


#: ``--image-scale`` of ``simsplat ingest`` for sources with camera images, when not given.
DEFAULT_IMAGE_SCALE = 0.5


@app.command("ingest", no_args_is_help=True)
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
    logs = _run_flow(
        ingest_flow, RunnerKind.threads, 1, store_root=out, source=chosen.name, paths=[str(path)], image_scale=scale
    )
    _print_logs(logs)


@app.command()
def inspect(
    log_dir: Annotated[str, typer.Argument(help="A stored log: STORE/logs/<seq_id>.")],
    sheet: Annotated[
        Path | None, typer.Option(help="Write a contact sheet PNG (all cameras + bird's-eye view).")
    ] = None,
    frame: Annotated[int, typer.Option(help="Frame shown on the contact sheet.")] = 0,
) -> None:
    """Summarise a stored log and optionally draw its projected 3D boxes on one frame."""
    from simsplat_core.summary import summarize_log
    from simsplat_core.viz.contact_sheet import contact_sheet
    from storage import ArtifactStore, read_scene_log
    from storage.png import write_png

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
        try:
            uri = write_png(sheet, contact_sheet(log, frame))
        except (OSError, ValueError) as exc:
            raise typer.BadParameter(f"could not write {sheet}: {exc}", param_hint="--sheet") from exc
        console.print(f"contact sheet: {uri}")


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
