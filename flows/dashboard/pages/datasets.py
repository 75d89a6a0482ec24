"""The datasets pages: ``/datasets`` (every exported dataset of the store's listing) and ``/datasets/<name>`` (its
manifest checked against its files, its data card; ``?verify=1`` hashes every shard)."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.rendering import DashboardState, NotFound, page
from tasks.dashboard.datasets import DatasetsView, DatasetView, read_dataset, read_datasets

router = APIRouter()


@page(router, "/datasets", "datasets.html", title="Datasets")
def datasets(state: DashboardState) -> DatasetsView:
    return read_datasets(state.store)


@page(router, "/datasets/{name}", "dataset.html", title=lambda view: f"Dataset {view.name}")
def dataset(state: DashboardState, name: str, verify: bool = False) -> DatasetView:
    view = read_dataset(state.store, name, verify=verify)
    if view is None:
        raise NotFound(f"dataset {name!r} is not in the store's listing")
    return view
