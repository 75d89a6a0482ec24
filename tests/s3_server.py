"""An S3-compatible server on 127.0.0.1 for tests (moto's server mode) and URIs into its buckets.

``S3Server`` starts ``moto.server.ThreadedMotoServer`` on a free port, creates the buckets, and names locations
in them the way a user does: ``s3://bucket/prefix?endpoint_override=127.0.0.1:PORT&scheme=http`` (the endpoint
as a URI option, credentials in the environment). ``aws_environment`` holds the fake credentials a test
process (and its subprocesses) read from the environment.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import pyarrow.fs as pafs

BUCKETS = ("store", "landing", "export")
#: Fake credentials: moto accepts any; they travel by the environment only.
AWS_ENVIRONMENT = {"AWS_ACCESS_KEY_ID": "moto-test-key", "AWS_SECRET_ACCESS_KEY": "moto-test-secret",
                   "AWS_DEFAULT_REGION": "us-east-1"}


@dataclass(frozen=True)
class S3Server:
    """A running server: ``host:port`` and the options a URI needs to reach it."""

    endpoint: str

    @property
    def options(self) -> str:
        """The URI query naming this endpoint (plain HTTP)."""
        return f"endpoint_override={self.endpoint}&scheme=http"

    def uri(self, bucket: str, prefix: str = "") -> str:
        """``s3://bucket/prefix?endpoint_override=...``."""
        return f"s3://{bucket}/{prefix.strip('/')}?{self.options}"

    def fresh_uri(self, bucket: str, label: str) -> str:
        """A location under a new, unique prefix of ``bucket`` (tests share the session's server and buckets)."""
        return self.uri(bucket, f"{label}-{uuid.uuid4().hex[:8]}")

    def objects(self, uri: str) -> dict[str, int]:
        """Every object below the location ``uri`` as the server lists it: path below it -> modification time (ns)."""
        base = uri.split("://", 1)[1].split("?", 1)[0].rstrip("/")
        selector = pafs.FileSelector(base, recursive=True, allow_not_found=True)
        return {info.path[len(base) + 1:]: int(info.mtime_ns or 0)
                for info in self.filesystem().get_file_info(selector) if info.type == pafs.FileType.File}

    def filesystem(self) -> pafs.S3FileSystem:
        """A filesystem on the server that sees every bucket (for listings in assertions)."""
        return pafs.S3FileSystem(endpoint_override=self.endpoint, scheme="http", region="us-east-1")


@contextmanager
def running_s3_server(buckets: tuple[str, ...] = BUCKETS) -> Iterator[S3Server]:
    """Start moto's server on a free port of 127.0.0.1 with ``buckets`` created; stopped on exit."""
    from moto.server import ThreadedMotoServer

    server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    try:
        host, port = server.get_host_and_port()
        running = S3Server(f"{host}:{port}")
        creator = pafs.S3FileSystem(endpoint_override=running.endpoint, scheme="http", region="us-east-1",
                                    allow_bucket_creation=True)
        for bucket in buckets:
            creator.create_dir(bucket)
        yield running
    finally:
        server.stop()
