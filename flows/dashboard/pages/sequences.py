"""The sequence pages: ``/sequences`` (every log of the store) and ``/sequences/{seq_id}`` (one log: contact sheet,
bird's-eye view, reconstruction quality, the language scene's objects, and a query box: ``?q=<description>``,
``&relevance=true`` adds the relevance maps)."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.rendering import DashboardState, NotFound, page
from tasks.dashboard.sequences import SequencesView, SequenceView, read_sequence, read_sequences

router = APIRouter()


@page(router, "/sequences", "sequences.html", title="Sequences")
def sequences(state: DashboardState) -> SequencesView:
    return read_sequences(state.store)


@page(router, "/sequences/{seq_id}", "sequence.html", title=lambda view: f"Sequence {view.seq_id}")
def sequence(state: DashboardState, seq_id: str, q: str = "", relevance: bool = False) -> SequenceView:
    view = read_sequence(state.store, state.made, seq_id, q, relevance)
    if view is None:
        raise NotFound(f"sequence {seq_id!r} is not in the store (see /sequences)")
    return view
