"""``simsplat assets build | list | sheet``: the asset bank of scene editing."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from flows.cli.printers import print_asset_listing, print_asset_sheet, print_built_bank

commands = typer.Typer(help="The asset bank of scene editing: build it, list it, draw its contact sheet.",
                       no_args_is_help=True)

BankOption = Annotated[str | None, typer.Option("--bank", help="Bank hash (or unique prefix); default: the newest.")]


@commands.command("build")
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
    print_built_bank(built)


@commands.command("list")
def assets_list(
    store: Annotated[str, typer.Option(help="Artifact store root.")],
    bank: BankOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the banks and the assets as one JSON object.")] = False,
) -> None:
    """List the stored asset banks and the assets of one (the newest unless --bank)."""
    from tasks.assets import list_assets

    try:
        listing = list_assets(store, bank)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--bank") from exc
    if as_json:
        typer.echo(json.dumps({"banks": listing.banks, "bank_hash": listing.bank_hash, "assets": listing.assets}))
        return
    print_asset_listing(listing)


@commands.command("sheet")
def assets_sheet(
    store: Annotated[str, typer.Option(help="Artifact store root.")],
    out: Annotated[str, typer.Option(help="PNG to write.")],
    bank: BankOption = None,
    columns: Annotated[int, typer.Option(min=1, help="Tiles per row.")] = 8,
) -> None:
    """Draw a bank's contact sheet: every asset rendered alone from the same 3/4 view, with its caption."""
    from flows.progress import StepBars
    from tasks.assets import draw_asset_sheet

    try:
        with StepBars(headline=""):
            sheet = draw_asset_sheet(store, out, bank, columns)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc), param_hint="--bank") from exc
    print_asset_sheet(sheet)
