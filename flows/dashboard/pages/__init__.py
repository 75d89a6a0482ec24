"""The dashboard's pages, one module per page group, each exposing ``router`` (``fastapi.APIRouter``) whose pages
are registered with ``flows.dashboard.rendering.page``. :data:`ROUTERS` lists them all."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.pages import datasets, evaluation, mining, overview, recordings, runs, scenarios, search, sequences

#: Every page group's router.
ROUTERS: tuple[APIRouter, ...] = (overview.router, runs.router, sequences.router, search.router, mining.router,
                                  recordings.router, scenarios.router, evaluation.router, datasets.router)
