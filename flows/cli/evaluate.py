"""``simsplat eval all | grounding | editing | mining | motion | search``: evaluate stored results and write the run's
tables (``OUT/tables/*.parquet`` + ``*.md`` + ``manifest.json``).

Every command prints the tables it wrote as their declarations (``TableSpec``) print them, read back from OUT.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from flows.cli.common import AlignedSeqOption, JsonOption, RunDirOption, option_names, stored_sequences
from flows.cli.printers import (
    editing_notes,
    evaluation_notes,
    mining_notes,
    motion_notes,
    print_lines,
    print_tables,
    report,
    table_locations,
)

commands = typer.Typer(help="Evaluate stored results and write the run's tables.", no_args_is_help=True)


def _show(out_root: str, notes: list[str], out_relpath: str = "") -> None:
    """The declared tables written under ``out_root``/``out_relpath``, then ``notes``."""
    from tasks.run_tables import load_run_tables

    print_tables(load_run_tables(out_root, out_relpath))
    print_lines(notes)


@commands.command("all")
def eval_all(
    store: Annotated[str, typer.Option(help="Artifact store root: every table its contents allow is computed.")],
    out: Annotated[str | None, typer.Option(help="Run directory for tables/, manifest.json and summary.md "
                                              "(default: STORE/runs/<run_id>/).")] = None,
    only: Annotated[list[str] | None, typer.Option(help="Evaluations to run (repeatable or comma separated; "
                                                   "default: all the store allows).")] = None,
    per_category: Annotated[int, typer.Option(min=1, help="Editing prompts per category.")] = 30,
    infeasible: Annotated[int, typer.Option(min=0, help="Infeasible editing prompts.")] = 20,
    per_sequence: Annotated[int, typer.Option(min=1, help="Mining: accepted scenarios wanted per sequence.")] = 3,
    clients: Annotated[str, typer.Option(help="Mining VLM clients, comma separated: rule, openai (run only when "
                                         "SIMSPLAT_VLM_URL and SIMSPLAT_VLM_MODEL are set).")] = "rule,openai",
    seed: Annotated[int, typer.Option(help="Seed of the prompt sets and the mining loop.")] = 0,
    as_json: JsonOption = False,
) -> None:
    """Every evaluation the store's contents allow (reconstruction, throughput, grounding, editing, motion,
    mining, search) into one run directory: each table as Parquet + Markdown, a manifest (code version, config,
    the store's content keys, wall time per table) and summary.md; what cannot run is skipped with the reason."""
    from flows.progress import StepBars
    from tasks.eval_all import EvalAllConfig, evaluate_all

    config = EvalAllConfig(groups=option_names(only) or None, per_category=per_category, infeasible=infeasible,
                           per_sequence=per_sequence, clients=option_names([clients]), seed=seed)
    try:
        with StepBars(headline=""):
            result = evaluate_all(store, out_root=out, config=config)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise typer.BadParameter(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)) from exc
    report(result, as_json, lambda r: _show(r.out_root, evaluation_notes(r), r.out_relpath))


@commands.command("grounding")
def eval_grounding(
    store: Annotated[str, typer.Option(help="Artifact store root with synthetic logs and aligned scenes.")],
    out: RunDirOption,
    seq: AlignedSeqOption = None,
) -> None:
    """Grounding benchmark (SIMSplat Tables 2 and 3): paraphrased queries from the logs' ground truth,
    accuracy and vIoU per category for the baselines, this method and its feature ablation."""
    from tasks.grounding_eval import evaluate_grounding_run

    seq_ids = stored_sequences(store, seq, "language")
    try:
        result = evaluate_grounding_run.fn(store, seq_ids, out)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    _show(out, table_locations(result))


@commands.command("editing")
def eval_editing(
    store: Annotated[str, typer.Option(help="Artifact store root with synthetic logs, aligned scenes and an asset "
                                       "bank (`simsplat assets build`).")],
    out: RunDirOption,
    seq: AlignedSeqOption = None,
    per_category: Annotated[int, typer.Option(min=1, help="Prompts per category of Table 3, over all sequences.")] = 30,
    infeasible: Annotated[int, typer.Option(min=0, help="Infeasible prompts (they must be refused).")] = 20,
    methods: Annotated[list[str] | None, typer.Option(help="ours / chatsim-like / omnire-like (repeatable or comma "
                                                      "separated; default: all).")] = None,
    render_all: Annotated[bool, typer.Option("--render-all", help="Render every frame of every edit (default: the "
                                             "test frames and the frames where the edit is seen).")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the prompt set.")] = 0,
    as_json: JsonOption = False,
) -> None:
    """Language editing benchmark (SIMSplat Table 3): prompts written from the synthetic worlds' ground truth,
    each edit checked against ground truth (trajectories, renders, captions), completion per category for this
    editor and the ChatSim-like / OmniRe-like variants, infeasible prompts refused, and edit fidelity against the
    world's own rendering of each edit."""
    from flows.progress import StepBars
    from tasks.editing_eval import evaluate_editing_run

    seq_ids = stored_sequences(store, seq, "language")
    names = option_names(methods) or None
    try:
        with StepBars(headline=""):
            result = evaluate_editing_run.fn(store, seq_ids, out, per_category=per_category, infeasible=infeasible,
                                             methods=names, render_all=render_all, seed=seed)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    report(result, as_json, lambda r: _show(out, editing_notes(r)))


@commands.command("mining")
def eval_mining(
    store: Annotated[str, typer.Option(help="Artifact store root with aligned scenes and an asset bank; the mined "
                                       "scenarios are stored in it under edits/evalmine-<client>-<time>/.")],
    out: RunDirOption,
    seq: AlignedSeqOption = None,
    per_sequence: Annotated[int, typer.Option(min=1, help="Accepted scenarios wanted per sequence.")] = 3,
    max_attempts: Annotated[int, typer.Option(min=1, help="Attempts per proposal.")] = 3,
    clients: Annotated[str, typer.Option(help="VLM clients, comma separated: rule, openai (run only when "
                                         "SIMSPLAT_VLM_URL and SIMSPLAT_VLM_MODEL are set).")] = "rule,openai",
    seed: Annotated[int, typer.Option(help="Seed of the mining loop (and of the rule-based client).")] = 0,
    as_json: JsonOption = False,
) -> None:
    """Mining benchmark (SIMSplat Table 5 analogue): mine every sequence per VLM client; completion, mean attempts
    to acceptance, mean plausibility, accepted scenarios re-checked for collisions and off-road agents, acceptance
    by edit category, where the time goes (accepted scenarios per hour per core), and the search benchmark of the same
    sequences (tables/search: RefAV timestamp and log balanced accuracy per query)."""
    from flows.progress import StepBars
    from tasks.mining_eval import evaluate_mining_run
    from tasks.search_eval import search_run_table

    seq_ids = stored_sequences(store, seq, "language")
    names = option_names([clients])
    try:
        with StepBars(headline=""):
            result = evaluate_mining_run.fn(store, seq_ids, out, clients=names, per_sequence=per_sequence,
                                            max_attempts=max_attempts, seed=seed, search_table=search_run_table)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    report(result, as_json, lambda r: _show(out, mining_notes(r)))


#: Real driving-log samples beside the repository (``../shared/data``), the default of ``eval motion --real``.
SHARED_REAL_LOGS: tuple[str, ...] = ("waymo/motion_data_one_scenario.tfrecord", "av2/sensor-log-7fab2350",
                                     "av2/forecasting-0a1e6f0a")


def default_real_logs(root: Path | None = None) -> list[Path]:
    """The real-log samples under ``<repo>/../shared/data`` that exist (none when it is absent)."""
    base = (root if root is not None else Path(__file__).resolve().parents[2]).parent / "shared" / "data"
    return [base / rel for rel in SHARED_REAL_LOGS if (base / rel).exists()]


@commands.command("motion")
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
    window_stride: Annotated[int, typer.Option(min=1, help="Steps between the starts of the 9.1 s windows each "
                                               "real log is cut into (its rows average over them).")] = 10,
    diagnose: Annotated[bool, typer.Option("--diagnose", help="Also list every agent stopped in a real rollout "
                                           "but moving in the log, with its blocker, the rule that stopped it and "
                                           "the distance (tables/motion_stalls).")] = False,
    as_json: JsonOption = False,
) -> None:
    """Multi-agent refinement: the ``motion`` table. Synthetic rows: the editing benchmark's insert /
    modify prompts and interaction prompts applied to the store's scenes with refinement none / single-agent /
    full; real rows: the predictors rolled out on real logs (the ego replays its log, every other agent is
    predicted from 1.1 s of history) against the logged future; real edit rows: scripted edits of the real logs
    (lead vehicle brakes, stopped truck, jaywalker) in every mode. Columns: collision, off-road, kinematic and
    overall failure rates (per scenario and per agent), progress, stopped agents, ADE at 3 s and 8 s."""
    from flows.progress import StepBars
    from simsplat_core.data.errors import CorruptLogError
    from simsplat_core.motion.registry import available_predictors
    from tasks.motion_eval import RealOptions, evaluate_motion_run

    names = option_names(predictor) or [n for n in available_predictors() if n != "log"]
    seq_ids = stored_sequences(store, seq, "language") if store is not None else []
    if seq and store is None:
        raise typer.BadParameter("--seq needs --store", param_hint="--seq")
    paths = list(real) if real else default_real_logs()
    if not paths and not seq_ids:
        raise typer.BadParameter("no real logs given and no samples under ../shared/data", param_hint="--real")
    try:
        with StepBars(headline=""):
            result = evaluate_motion_run.fn(out, paths, names, store_root=store, seq_ids=seq_ids,
                                            edit_predictor=edit_predictor,
                                            per_category=per_category, per_kind=per_kind,
                                            options=RealOptions(window_stride, diagnose, not no_real_edits))
    except CorruptLogError as exc:
        raise typer.BadParameter(f"damaged log: {exc}", param_hint="--real") from exc
    except KeyError as exc:
        raise typer.BadParameter(str(exc.args[0]) if exc.args else str(exc), param_hint="--predictor") from exc
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--real") from exc
    report(result, as_json, lambda r: _show_motion(out, r))


def _show_motion(out: str, result: Any) -> None:
    """The motion tables and notes, then the stalled agents when diagnosed."""
    _show(out, motion_notes(result))
    if result.stalls_table:
        from flows.cli.printers import print_tables
        from simsplat_core.eval.refinement.diagnosis import STALLS_SPEC, stalls_table

        print_tables([(STALLS_SPEC, stalls_table(result.stalls))])


@commands.command("search")
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
    _show(out, [str(summary)])
