"""Everything the ``simsplat`` commands print for people: one function per result, rich tables on stdout.

On a terminal tables fit its width; on a pipe or a file (scripts, CI logs, ``| tee``) nothing wraps: rich's default
of 80 columns would fold every wide table into unreadable cells.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

#: Console width when stdout is not a terminal: wide enough that no table or line wraps.
PIPE_WIDTH = 100_000


def console() -> Console:
    """A rich console on the current stdout: the terminal's width (or ``COLUMNS``), else :data:`PIPE_WIDTH`."""
    if sys.stdout.isatty() or "COLUMNS" in os.environ:
        return Console()
    return Console(width=PIPE_WIDTH)


def report(result: Any, as_json: bool, printer: Callable[[Any], None]) -> None:
    """An evaluation's result: one JSON object on stdout (``--json``, dataclass fields) or ``printer``'s tables."""
    if as_json:
        typer.echo(json.dumps(asdict(result), default=float))
        return
    printer(result)


# ------------------------------------------------------------------------------------------- logs, scenes, language
def print_logs(logs: Sequence[Any]) -> None:
    """Stored logs (``tasks.logs.StoredLog``): source, size, objects, whether written now."""
    table = Table(title="Driving logs")
    for col in ("sequence", "source", "frames", "cameras", "MB", "seconds", "status"):
        table.add_column(col, no_wrap=True)
    table.add_column("objects")
    for s in logs:
        objects = ", ".join(f"{n} {c}" for c, n in s.summary.objects_by_category.items())
        table.add_row(s.summary.seq_id, s.summary.source, str(s.summary.num_frames), str(len(s.summary.cameras)),
                      f"{s.bytes_on_disk / 1e6:.1f}", f"{s.seconds:.1f}", "skipped" if s.skipped else "written",
                      objects)
    console().print(table)


def print_log_summary(summary: Any, sheet_uri: str = "") -> None:
    """One stored log (``simsplat_core.summary.LogSummary``) and where its contact sheet went."""
    out = console()
    table = Table(title=f"{summary.seq_id} ({summary.source})", show_header=False)
    table.add_row("frames", f"{summary.num_frames} over {summary.duration_s:.1f} s; test frames {summary.test_frames}")
    table.add_row("cameras", ", ".join(f"{c} {wh}" for c, wh in summary.cameras.items()) or "none")
    table.add_row("objects", ", ".join(f"{n} {c}" for c, n in summary.objects_by_category.items()) or "none")
    table.add_row("map", ", ".join(f"{n} {k}" for k, n in summary.map_by_kind.items()) or "none")
    out.print(table)
    if sheet_uri:
        out.print(f"contact sheet: {sheet_uri}")


def print_scenes(scenes: Sequence[Any]) -> None:
    """Reconstructed scenes (``tasks.reconstruct.StoredScene``) with their test metrics."""
    table = Table(title="Reconstructed scenes (PSNR/SSIM on held-out test frames)")
    for col in ("sequence", "scene", "PSNR dB", "SSIM", "Gaussians", "seconds", ""):
        table.add_column(col, no_wrap=True)
    for s in scenes:
        m = s.metrics
        table.add_row(s.seq_id, s.scene_hash[:8], f"{m.get('psnr_test', float('nan')):.2f}",
                      f"{m.get('ssim_test', float('nan')):.3f}", str(int(m.get("num_gaussians", 0))),
                      f"{s.seconds:.1f}", "skipped" if s.skipped else "")
    console().print(table)


def print_stages(stages: Sequence[Any], only: tuple[str, ...] | None = None) -> None:
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
    console().print(table)


def print_language(aligner: Any, scenes: Sequence[Any]) -> None:
    """Language scenes (``tasks.align.StoredLanguageScene``) built with the motion aligner ``aligner``."""
    table = Table(title=f"Language scenes (motion aligner {aligner.model_hash[:8]})")
    for col in ("sequence", "objects", "app", "motion", "mask IoU", "seconds", ""):
        table.add_column(col, no_wrap=True)
    for s in scenes:
        m = s.metrics
        table.add_row(s.seq_id, str(int(m.get("object_nodes", 0))), str(int(m.get("nodes_with_f_app", 0))),
                      str(int(m.get("nodes_with_motion", 0))), f"{m.get('mask_pooled_iou', float('nan')):.3f}",
                      f"{s.seconds:.1f}", "skipped" if s.skipped else "")
    console().print(table)


def print_artifacts(store: str) -> None:
    """Where ``simsplat run`` put its artifacts."""
    console().print(f"Artifacts under [bold]{store}[/bold]: logs/<seq_id>/ (Parquet tables, EXR images), "
                    "scenes/<seq_id>/<scene_hash>/ (Gaussians, nodes, poses, metrics, test renders), "
                    "alignment/<model_hash>/ (motion aligner, language scenes).")


def print_rendered(seq_id: str, frame: int, scene_hash: str, shift_left: float, shift_forward: float,
                   uri: str) -> None:
    """Where ``simsplat render`` wrote its picture."""
    console().print(f"{seq_id} frame {frame} (scene {scene_hash[:12]}, shift left {shift_left:g} m, "
                    f"forward {shift_forward:g} m): {uri}")


# ------------------------------------------------------------------------------------------- query, search
def print_query(seq_id: str, text: str, answer: Any, top: int) -> None:
    """A grounding answer (``tasks.query.QueryAnswer``): the ``top`` ranked nodes, the message, the picture."""
    out = console()
    grounding = answer.grounding
    table = Table(title=f"{seq_id}: {text!r}")
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
    out.print(table)
    out.print(grounding.message)
    if answer.png_uri:
        out.print(f"frame {answer.frame}: {answer.png_uri}")


def print_search(text: str, found: Any) -> None:
    """Search hits (``simsplat_core.search.logs.StoreSearch``), ranked, with their pictures."""
    out = console()
    table = Table(title=f"search: {text!r}")
    for column in ("rank", "sequence", "objects", "frames", "score", "picture"):
        table.add_column(column)
    for rank, hit in enumerate(found.hits, start=1):
        table.add_row(str(rank), hit.seq_id, ", ".join(hit.object_ids), f"{hit.window[0]}-{hit.window[1]}",
                      f"{hit.score:.2f}", hit.picture or "-")
    out.print(table)
    out.print(found.message)


# ------------------------------------------------------------------------------------------- edit, mine, assets
def print_edit(result: Any, data: dict[str, Any]) -> None:
    """One edit attempt (``tasks.edit.EditRun``) and its JSON answer ``data`` (``tasks.answers.edit_as_dict``)."""
    out = console()
    out.print(f"{result.seq_id}: {result.prompt!r}", soft_wrap=True)
    if result.program is not None:
        for k, command in enumerate(result.program.commands):
            compact = command.model_dump(mode="json", exclude_defaults=True, exclude={"note"})
            out.print(f"  command {k + 1}: {json.dumps(compact, separators=(',', ':'))}", markup=False,
                      soft_wrap=True)
    if result.status != "succeeded":
        out.print(f"[bold red]{result.status}[/bold red] ({result.reason}): {result.message}", soft_wrap=True)
        return
    for grounded, change in zip(data["grounded"], data["changes"]):
        found = [f"{o} (node {n})" for o, n in zip(grounded["target_object_ids"], grounded["target_node_ids"])]
        anchors = [f"{o} (node {n})" for o, n in zip(grounded["anchor_object_ids"], grounded["anchor_node_ids"])]
        if found:
            out.print(f"  grounded target: {', '.join(found)}", markup=False, soft_wrap=True)
        if anchors:
            out.print(f"  grounded anchor: {', '.join(anchors)}", markup=False, soft_wrap=True)
        out.print(f"  changed: {change}", markup=False, soft_wrap=True)
    reaction = data.get("refinement")
    if reaction:
        reacted = ", ".join(reaction["refined"]) or "nobody"
        out.print(f"  traffic ({reaction['mode']}, {reaction['predictor']}): reacted: {reacted}", markup=False,
                  soft_wrap=True)
        by_reason: dict[str, list[str]] = {}
        for oid, why in reaction["replayed"].items():
            by_reason.setdefault(why, []).append(oid)
        for why, oids in by_reason.items():
            out.print(f"  replay their log ({why}): {', '.join(oids)}", markup=False, soft_wrap=True)
    validation = data["validation"]
    verdict = "[green]ok[/green]" if validation["ok"] else "[bold yellow]problems[/bold yellow]"
    out.print(f"validation of {validation['checked']} edited / reacting agent(s): {verdict}")
    for line in validation["failures"]:
        out.print(f"  - {line}", markup=False, soft_wrap=True)
    total = result.bytes.get("total", 0)
    timing = ", ".join(f"{k} {v:.1f}" for k, v in result.seconds.items() if k != "total")
    out.print(f"edit {result.edit_id}{' (already stored)' if result.skipped else ''}: {result.edit_uri} "
              f"({total / 1e6:.2f} MB) in {result.seconds.get('total', 0.0):.1f} s ({timing})", markup=False,
              soft_wrap=True)


def print_mining(data: dict[str, Any]) -> None:
    """Mined scenarios (``tasks.answers.mining_as_dict``) and the totals."""
    out = console()
    table = Table(title=f"Scenarios mined (run {data['run_id']})")
    for col in ("sequence", "prompt", "category", "attempts", "plausibility", "edit dir"):
        table.add_column(col)
    for sc in data["scenarios"]:
        plaus = "" if sc["plausibility"] is None else str(sc["plausibility"])
        table.add_row(sc["seq_id"], sc["prompt"], sc["category"], str(sc["attempts"]), plaus, sc["edit_dir"])
    out.print(table)
    totals = data["totals"]
    per = ", ".join(f"{k} {v}" for k, v in totals["per_category"].items()) or "none"
    out.print(f"{totals['accepted']} accepted of {totals['attempts']} attempt(s) in {totals['sequences']} "
              f"sequence(s) ({per}); every attempt: {data['edits_table']}", markup=False, soft_wrap=True)


def print_nothing_new(result: Any) -> None:
    """A main run that found nothing new (``flows.pipeline.idle_main_run``): what the store holds, the run record."""
    console().print(f"Nothing new: {len(result.logs)} log(s), {len(result.scenes)} scene(s) and {len(result.language)} "
                    "language scene(s) stored; nothing left to ingest, reconstruct, align or mine with these "
                    f"settings. Every stage skipped (run {result.run_id}).", markup=False, soft_wrap=True)


def print_built_bank(built: Any) -> None:
    """A built (or found) asset bank (``tasks.assets.BuiltBank``): the cut-out report and the totals."""
    out = console()
    for line in built.report:
        out.print(line, markup=False, highlight=False)
    counts = ", ".join(f"{n} {c}" for c, n in sorted(built.by_category.items()))
    status = "already built, skipped" if built.skipped else f"built in {built.seconds:.1f} s"
    out.print(f"asset bank {built.bank_hash[:12]}: {built.assets} assets ({counts}), {built.gaussians} Gaussians, "
              f"{built.bytes / 1e6:.1f} MB; {status}\n  {built.uri}")
    if built.sheet_uri:
        out.print(f"contact sheet: {built.sheet_uri}")


def print_asset_listing(listing: Any) -> None:
    """The store's asset banks and the assets of one (``tasks.assets.AssetListing``)."""
    out = console()
    banks = Table(title=f"Asset banks in {listing.uri}")
    for col in ("bank", "assets", "by category", "written"):
        banks.add_column(col, no_wrap=True)
    for b in listing.banks:
        banks.add_row(b["bank_hash"][:12] + (" *" if b["bank_hash"] == listing.bank_hash else ""), str(b["assets"]),
                      ", ".join(f"{n} {c}" for c, n in sorted((b["by_category"] or {}).items())),
                      str(b["written_at"] or ""))
    out.print(banks)
    table = Table(title=f"Assets of bank {listing.bank_hash[:12]}")
    for col in ("asset", "category", "subtype", "colour", "caption", "size m", "Gaussians", "source"):
        table.add_column(col)
    for r in listing.assets:
        source = f"{r['source_seq']} {r['source_object']}".strip() or "procedural"
        table.add_row(r["asset_id"], r["category"], r["subtype"], r["color"], r["caption"],
                      " x ".join(f"{v:.2f}" for v in r["size"]), str(r["num_gaussians"]), source)
    out.print(table)


def print_asset_sheet(sheet: Any) -> None:
    """Where a bank's contact sheet went (``tasks.assets.AssetSheet``)."""
    console().print(f"contact sheet of bank {sheet.bank_hash[:12]} ({sheet.assets} assets): {sheet.uri}")


# ------------------------------------------------------------------------------------------- evaluations
def print_tables(tables: Sequence[tuple[Any, Any]]) -> None:
    """Declared evaluation tables, each as its ``TableSpec`` prints it (``(spec, pyarrow.Table)`` pairs, e.g. from
    ``tasks.run_tables.load_run_tables``): the same columns, rows and formats as the table's Markdown."""
    out = console()
    for spec, table in tables:
        header, rows = spec.rows_for_console(table)
        shown = Table(title=spec.title)
        for name in header:
            shown.add_column(name)
        for row in rows:
            shown.add_row(*row)
        out.print(shown)


def print_lines(lines: Sequence[str]) -> None:
    """Notes under the tables (timings, failed re-checks, where the tables went), as they are (no markup)."""
    out = console()
    for line in lines:
        out.print(line, markup=False, soft_wrap=True)


def table_locations(result: Any) -> list[str]:
    """``name: uri`` of every table an evaluation wrote (its ``tables`` mapping)."""
    return [f"{name}: {uri}" for name, uri in result.tables.items()]


def editing_notes(result: Any) -> list[str]:
    """The editing benchmark's edit timings per method, then where its tables went."""
    timings = [f"{method}: one edit {stats['median']:.2f} s median, {stats['max']:.2f} s max"
               for method, stats in result.edit_seconds.items() if stats]
    return timings + table_locations(result)


def mining_notes(result: Any) -> list[str]:
    """The mining benchmark's throughput per client, accepted scenarios failing the re-check, where its tables
    went."""
    lines = [f"{row['client']}: {row['seconds']:.0f} s, {row['accepted_per_hour_per_core']:.1f} accepted scenarios "
             f"per hour per core ({result.cores} core(s))" for row in result.stages if row["stage"] == "total"]
    lines += [f"accepted but failing on re-check: {line}" for line in result.failed_scenarios]
    return lines + table_locations(result)


def motion_notes(result: Any) -> list[str]:
    """The scripted real edits applied (or why not), then where the motion table went."""
    lines = [f"real edits of {seq_id}: " + "; ".join(f"{e} applied" if not why else f"{e}: {why}"
                                                    for e, why in edits.items())
             for seq_id, edits in result.real_edits.items()]
    return [*lines, f"motion: {result.table}"]


def evaluation_notes(result: Any) -> list[str]:
    """``simsplat eval all``: each table's wall time, what was skipped and why, where the summary went."""
    lines = [f"{name}: {seconds:.1f} s" for name, seconds in result.seconds.items()]
    lines += [f"skipped {name}: {why}" for name, why in result.skipped.items()]
    return [*lines, f"tables, manifest and summary: {result.run_dir}"]


def print_text(text: Any) -> None:
    """A line (or any printable) as it is, e.g. the search benchmark's summary."""
    console().print(text)


# ------------------------------------------------------------------------------------------- export
def print_export(result: Any) -> None:
    """What ``simsplat export`` wrote (``tasks.export.ExportResult``): new scenarios by split, shards by format,
    the dataset's counts, what was left out and why."""
    out = console()
    table = Table(title=f"Dataset {result.dataset_uri}")
    for col in ("split", "new scenarios", "in dataset"):
        table.add_column(col)
    for split, total in sorted(result.counts.get("by_split", {}).items()):
        table.add_row(split, str(len(result.new_scenarios.get(split, ()))), str(total))
    out.print(table)
    shards = Table(title="Shards written" if result.shards else "No new shards: the dataset was up to date")
    for col in ("format", "files", "MB"):
        shards.add_column(col)
    by_format: dict[str, list[Any]] = {}
    for shard in result.shards:
        by_format.setdefault(shard.format, []).append(shard)
    for fmt, items in by_format.items():
        shards.add_row(fmt, str(len(items)), f"{sum(s.bytes for s in items) / 1e6:.2f}")
    out.print(shards)
    lines = [f"{result.written} new, {result.skipped_existing} already in the dataset, {len(result.left_out)} left "
             f"out, in {result.seconds.get('total', 0.0):.1f} s (read {result.seconds.get('read', 0.0):.1f}, validate "
             f"{result.seconds.get('validate', 0.0):.1f}, write {result.seconds.get('write', 0.0):.1f})"]
    lines += [f"left out {sid}: {why}" for sid, why in result.left_out.items()]
    print_lines(lines)


# ------------------------------------------------------------------------------------------- deploy
def print_deploy_findings(findings: Sequence[Any], files: Sequence[Any]) -> None:
    """Problems in the deployment files (``flows.deploy_check.Finding``), or that ``files`` passed."""
    out = console()
    if not findings:
        out.print(f"deployment files ok: {', '.join(str(f) for f in files)}", markup=False)
        return
    table = Table(title=f"Deployment files: {len(findings)} problem(s)")
    for col in ("file", "deployment / part", "field"):
        table.add_column(col, no_wrap=True)
    table.add_column("problem")
    for f in findings:
        table.add_row(f.file, f.item, f.field, f.problem)
    out.print(table)
