"""The overview page: what the store holds, counted per kind of artifact."""

from __future__ import annotations

from dataclasses import dataclass

from storage.datasets import list_datasets
from storage.inventory import LANGUAGE_SCENE, SCENE, sequences_with
from storage.logs import list_logs
from storage.runs import RUNS_DIR
from storage.store import ArtifactStore
from tasks.dashboard.sections import Section, section


@dataclass(frozen=True)
class StoreCounts:
    """How many of each artifact the store holds.

    Attributes:
        logs: complete logs; scenes: logs with a reconstructed scene; language_scenes: logs with a language scene;
        runs: run folders; edit_runs: runs (or ``manual``) with edits; datasets: exported datasets.
    """

    logs: int
    scenes: int
    language_scenes: int
    runs: int
    edit_runs: int
    datasets: int


@dataclass(frozen=True)
class OverviewView:
    """Attributes: store: the store's URI; exists: whether it is there at all; counts: what it holds."""

    store: str
    exists: bool
    counts: Section[StoreCounts]


def _counts(store: ArtifactStore) -> StoreCounts:
    return StoreCounts(logs=len(list_logs(store)), scenes=len(sequences_with(store, SCENE)),
                       language_scenes=len(sequences_with(store, LANGUAGE_SCENE)),
                       runs=len(store.listdir(RUNS_DIR)), edit_runs=len(store.listdir("edits")),
                       datasets=len(list_datasets(store)))


def read_overview(store: ArtifactStore) -> OverviewView:
    """The overview of ``store`` (a missing store says so; nothing is created)."""
    exists = store.is_dir("")
    counts = section("store contents", lambda: _counts(store)) if exists else Section(
        "store contents", error=f"the store {store.uri()} does not exist (make one with `simsplat run --store DIR`)")
    return OverviewView(store.uri(), exists, counts)
