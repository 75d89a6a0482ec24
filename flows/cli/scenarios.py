"""``simsplat edit | mine``: make scenarios from aligned scenes, one edit from language or many mined by a VLM loop."""

from __future__ import annotations

import dataclasses
import json
import logging
from pathlib import Path
from typing import Annotated

import typer

from flows.cli.common import VLMOption, check_vlm, stored_asset_bank, stored_sequences
from flows.cli.printers import print_edit, print_mining

commands = typer.Typer()
logger = logging.getLogger(__name__)


@commands.command()
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
    from storage.errors import MissingInputError
    from tasks.answers import edit_as_dict
    from tasks.edit import run_edit
    from tasks.stored_edits import load_edit_context

    try:
        motion_predictor = make_predictor(predictor)
    except KeyError as exc:
        raise typer.BadParameter(str(exc.args[0]), param_hint="--predictor") from exc
    options = dataclasses.replace(DEFAULT_OPTIONS, refinement="none" if no_refine else "full",
                                  ego_reacts=not (no_refine or ego_replays))
    if prompt is None and commands is None:
        raise typer.BadParameter("give a PROMPT or --commands FILE.json", param_hint="PROMPT")
    commands_json = None
    if commands is not None:
        try:
            commands_json = commands.read_text(encoding="utf-8")
        except OSError as exc:
            raise typer.BadParameter(f"cannot read {commands}: {exc}", param_hint="--commands") from exc
    try:
        loaded = load_edit_context(store, seq, predictor=motion_predictor)  # the store, opened once
    except MissingInputError as exc:
        raise typer.BadParameter(str(exc), param_hint="--seq") from exc
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
    data = edit_as_dict(result, loaded.ctx.graph)
    if as_json:
        typer.echo(json.dumps(data, allow_nan=False))
        raise typer.Exit(code)
    print_edit(result, data)
    raise typer.Exit(code)


@commands.command()
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
    from storage.runs import new_run_id
    from tasks.answers import mining_as_dict
    from tasks.mine import compact_mining_run, mine_sequence_task

    check_vlm(vlm)
    seq_ids = stored_sequences(store, seq, "language")
    stored_asset_bank(store, seq_ids)  # logs without images need none (box-only inserts)
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
    finally:
        compact_mining_run(store, run_id)
    data = mining_as_dict(run_id, summaries)
    if as_json:
        typer.echo(json.dumps(data, allow_nan=False))
        return
    print_mining(data)
