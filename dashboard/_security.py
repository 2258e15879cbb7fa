"""Who may talk to the bench: Origin checks, the access token and the control lease.

One client controls the drive at a time; every other client watches. Taking control from another
client is explicit (``take_over=True``) and visible to everybody through :meth:`ControlLease.holder`
and the change callbacks.
"""

from __future__ import annotations

import hmac
import secrets
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

from dashboard.config import is_loopback

__all__ = [
    "ControlLease",
    "Holder",
    "LeaseError",
    "allowed_hosts",
    "allowed_origins",
    "bearer",
    "host_ok",
    "origin_ok",
    "token_ok",
]


class LeaseError(Exception):
    """The caller does not hold control (or cannot take it without ``take_over``)."""


@dataclass(frozen=True)
class Holder:
    """The client in control: its secret token, a display name and since when (UNIX s)."""

    token: str
    client: str
    since: float

    def public(self) -> dict[str, Any]:
        """The holder without its secret."""
        return {"client": self.client, "since": self.since}


class ControlLease:
    """A single-holder control lease shared by the REST API and the GUI."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._holder: Holder | None = None
        self._callbacks: list[Callable[[Holder | None, Holder | None], None]] = []
        self.events: list[dict[str, Any]] = []

    @property
    def holder(self) -> Holder | None:
        return self._holder

    def on_change(self, cb: Callable[[Holder | None, Holder | None], None]) -> None:
        """Call ``cb(old, new)`` after every change of holder (on the changing thread)."""
        self._callbacks.append(cb)

    def acquire(self, client: str, *, take_over: bool = False, token: str | None = None) -> Holder:
        """Give control to ``client``; raise LeaseError if another holds it and not ``take_over``.

        ``token`` lets a caller (the GUI) choose its own secret; otherwise a random one is made.
        Re-acquiring with the current holder's own token keeps the lease.
        """
        client = client.strip()[:64] or "anonymous"
        with self._lock:
            old = self._holder
            if old is not None and token is not None and hmac.compare_digest(old.token, token):
                return old
            if old is not None and not take_over:
                raise LeaseError(f"{old.client} controls the bench; watch, or take over explicitly")
            new = Holder(token or secrets.token_urlsafe(16), client, time.time())
            self._holder = new
            self.events.append(
                {"t": new.since, "client": client, "took_from": old.client if old else None}
            )
            del self.events[:-50]
        for cb in list(self._callbacks):
            cb(old, new)
        return new

    def check(self, token: str | None) -> Holder:
        """Return the holder if ``token`` is its token, else raise LeaseError."""
        holder = self._holder
        if holder is None:
            raise LeaseError("nobody controls the bench: acquire control first (POST /api/control)")
        if token is None or not hmac.compare_digest(holder.token, token):
            raise LeaseError(f"{holder.client} controls the bench; you are watching")
        return holder

    def release(self, token: str | None) -> None:
        """Give control back; raise LeaseError unless ``token`` holds it."""
        with self._lock:
            old = self._holder
            if old is None or token is None or not hmac.compare_digest(old.token, token):
                raise LeaseError("you do not hold control")
            self._holder = None
        for cb in list(self._callbacks):
            cb(old, None)


def allowed_origins(host: str, ports: list[int], extra: list[str] | None = None) -> set[str]:
    """The browser origins that may open a WebSocket: the bench's own pages, plus ``extra``."""
    names = {host}
    if is_loopback(host) or host in ("0.0.0.0", "::"):
        names |= {"127.0.0.1", "localhost", "[::1]"}
    out = {f"http://{n}:{p}" for n in names for p in ports}
    out |= {o.rstrip("/") for o in (extra or [])}
    return out


def origin_ok(origin: str | None, allowed: set[str]) -> bool:
    """True when a WebSocket's Origin header is one of ``allowed``.

    No Origin header means a non-browser client (scripts, tests): browsers always send one on
    WebSockets, so a missing header cannot come from a cross-site page.
    """
    if origin is None:
        return True
    parts = urlsplit(origin)
    if not parts.scheme or not parts.netloc:
        return False
    return f"{parts.scheme}://{parts.netloc}".lower() in {a.lower() for a in allowed}


def token_ok(expected: str | None, given: str | None) -> bool:
    """Constant-time token comparison; no expected token means none is needed."""
    if expected is None:
        return True
    return given is not None and hmac.compare_digest(expected, given)


def allowed_hosts(host: str) -> set[str]:
    """Host names (without port) the bench answers to: loopback names, plus ``host`` itself
    (the configured bind address, e.g. with --allow-remote). Anything else is refused (421), so
    a page on a rebinding DNS name cannot read the bench."""
    names = {"127.0.0.1", "localhost", "[::1]", "::1"}
    if host not in ("0.0.0.0", "::", ""):
        names.add(host.lower())
    return names


def host_ok(host_header: str | None, allowed: set[str]) -> bool:
    """True when an HTTP Host header names one of ``allowed`` (the port is not compared: the
    request reached this socket, so it is ours)."""
    if not host_header:
        return False
    h = host_header.strip().lower()
    if h.startswith("["):
        name = h[: h.find("]") + 1] if "]" in h else h
    else:
        name = h.rsplit(":", 1)[0] if h.count(":") == 1 else h
    return name in allowed or name.strip("[]") in allowed


def bearer(authorization: str | None) -> str | None:
    """The token of an ``Authorization: Bearer <token>`` header (None otherwise)."""
    if not authorization:
        return None
    scheme, _, value = authorization.strip().partition(" ")
    if scheme.lower() != "bearer" or not value.strip():
        return None
    return value.strip()
