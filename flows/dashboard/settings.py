"""How the dashboard is served: the store it reads, the address it binds and the token a non-loopback address needs.

The token comes from the environment (``SIMSPLAT_DASHBOARD_TOKEN``) or the command line and is never logged.
"""

from __future__ import annotations

import ipaddress
import os
from dataclasses import dataclass

#: Environment variable holding the access token.
TOKEN_ENV = "SIMSPLAT_DASHBOARD_TOKEN"
#: Environment variable holding the dashboard's address, for links the flows publish ("http://host:8765").
URL_ENV = "SIMSPLAT_DASHBOARD_URL"
DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765


class UnsafeBindError(ValueError):
    """A non-loopback address without a token."""


def is_loopback(host: str) -> bool:
    """``host`` only accepts connections from this machine (``127.0.0.0/8``, ``::1``, ``localhost``)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass(frozen=True)
class DashboardSettings:
    """Attributes:
        store_root: the store (local path or object-store URI), read only.
        host, port: where the app listens.
        token: required of every request when set (``?token=``, ``Authorization: Bearer`` or the cookie the
            first tokened request sets); ``None``: no token (loopback only).
        refresh_s: how often a page showing a running run polls for changes, s.
    """

    store_root: str
    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT
    token: str | None = None
    refresh_s: float = 2.0

    def __post_init__(self) -> None:
        if not is_loopback(self.host) and not self.token:
            raise UnsafeBindError(f"binding the dashboard to {self.host!r} (not a loopback address) needs a token: "
                                  f"set {TOKEN_ENV} or pass --token")
        if not 0 < self.port < 65536:
            raise ValueError(f"port must be in 1..65535, got {self.port}")

    def __repr__(self) -> str:  # never show the token
        return (f"DashboardSettings(store_root={self.store_root!r}, host={self.host!r}, port={self.port}, "
                f"token={'set' if self.token else None})")


def token_from_env() -> str | None:
    """The token in ``SIMSPLAT_DASHBOARD_TOKEN`` (``None`` when unset or empty)."""
    return os.environ.get(TOKEN_ENV) or None


def dashboard_url() -> str | None:
    """The dashboard's address from ``SIMSPLAT_DASHBOARD_URL`` (no trailing slash), ``None`` when not configured."""
    url = os.environ.get(URL_ENV, "").strip()
    return url.rstrip("/") or None
