"""``simsplat query | render | search``: look into stored scenes and logs (interactive, no Prefect run)."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from flows.cli.printers import print_query, print_rendered, print_search

commands = typer.Typer()


@commands.command()
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
    from storage.errors import MissingInputError
    from tasks.render import render_view

    try:
        rendered = render_view(store, seq, frame, out, cameras=camera, shift_left=shift_left,
                               shift_forward=shift_forward, scene_hash=scene)
    except MissingInputError as exc:
        raise typer.BadParameter(str(exc), param_hint="--seq") from exc
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    print_rendered(seq, frame, rendered.scene_hash, shift_left, shift_forward, rendered.uri)


@commands.command()
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
    from tasks.answers import answer_as_dict
    from tasks.query import answer_query

    try:
        answer = answer_query(store, seq, text, out=out, frame=frame)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(answer_as_dict(answer, top), allow_nan=False))
        return
    print_query(seq, text, answer, top)


@commands.command()
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
    from tasks.answers import search_as_dict
    from tasks.search import search_store

    try:
        found = search_store(store, text, seq_ids=seq, top=top, out=out)
    except (FileNotFoundError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    if as_json:
        typer.echo(json.dumps(search_as_dict(found), allow_nan=False))
        return
    print_search(text, found)
