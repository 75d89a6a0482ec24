"""One Prefect API server for every test that runs a flow (starting one costs ~10 s)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def prefect_api_url():
    from flows.runtime import prefect_api

    with prefect_api() as url:
        yield url
