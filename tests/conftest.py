"""Fixtures shared by the whole suite."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO_ROOT.parent / "shared" / "data"

os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")
os.environ.setdefault("SIMSPLAT_PROGRESS", "0")
os.environ.setdefault("PREFECT_LOGGING_TO_API_WHEN_MISSING_FLOW", "ignore")


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """``../shared/data`` (real driving-log samples); the test is skipped when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real driving-log samples not found at {SHARED_DATA}")
    return SHARED_DATA


@pytest.fixture(scope="session")
def s3_server():
    """An S3-compatible server (moto) on 127.0.0.1 with the ``store``, ``landing`` and ``export`` buckets, and
    fake AWS credentials in the environment for the whole session (``tests.s3_server``)."""
    pytest.importorskip("moto.server", reason="moto[server] (a dev extra) is not installed")
    from tests.s3_server import AWS_ENVIRONMENT, running_s3_server

    with pytest.MonkeyPatch.context() as patch:
        for name, value in AWS_ENVIRONMENT.items():
            patch.setenv(name, value)
        with running_s3_server() as server:
            yield server
